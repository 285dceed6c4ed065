// Stopping a render from outside it: a flag the rows check between them.
#pragma once

#include <csignal>

namespace patchscan::render {

// Set by SIGINT and SIGTERM once CatchInterrupts has run (or by the program itself): the
// render stops at the next row and writes nothing.
extern volatile std::sig_atomic_t gInterrupted;

// Installs the handlers that set gInterrupted. A program calls it once; the library never does.
void CatchInterrupts();

}  // namespace patchscan::render
