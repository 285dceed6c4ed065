// The command-line reference (cli/reference.h): every option of every command is in the
// man page and in the Markdown page, both generated from the same definitions as --help.
#include <gtest/gtest.h>

#include "cli/app.h"
#include "cli/reference.h"

namespace patchscan::cli {
namespace {

// As the man page spells a name: hyphens as roff's minus sign.
std::string Roffed(const std::string& name) {
  std::string out;
  for (const char ch : name) out += ch == '-' ? std::string("\\-") : std::string(1, ch);
  return out;
}

TEST(Reference, EveryOptionOfEveryCommandIsDocumented) {
  Commands commands;
  const auto app = MakeApp(&commands, "test");
  RenderCommand mpiCommand;
  const auto mpi = MakeMpiApp(&mpiCommand, "test");
  const std::string man = ManPage(*app, *mpi, "test"), markdown = MarkdownReference(*app, *mpi);
  const std::vector<std::string> names = OptionNames(*app);
  // Every command's own options, not only help: render alone has more than twenty.
  EXPECT_GT(names.size(), 60u);
  for (const std::string& entry : names) {
    const std::string command = entry.substr(0, entry.find(' ')), option = entry.substr(entry.find(' ') + 1);
    // In the command's own section: after its heading, before the next command's.
    const auto section = [&](const std::string& text, const std::string& heading, const std::string& nextHeading) {
      const std::size_t at = text.find(heading);
      EXPECT_NE(at, std::string::npos) << heading;
      if (at == std::string::npos) return std::string();
      const std::size_t next = text.find(nextHeading, at + heading.size());
      return text.substr(at, next == std::string::npos ? std::string::npos : next - at);
    };
    EXPECT_NE(section(man, ".SH \"patchscan " + command + "\"", "\n.SH ").find(Roffed(option)), std::string::npos)
        << entry << " missing from the man page";
    EXPECT_NE(section(markdown, "## patchscan " + command + "\n", "\n## ").find(option), std::string::npos)
        << entry << " missing from docs/cli.md";
  }
}

// patchscan-mpi's reference says its render command takes patchscan render's options:
// so it must, every one, and the reference must have its section.
TEST(Reference, MpiTakesTheRenderOptions) {
  Commands commands;
  const auto app = MakeApp(&commands, "test");
  RenderCommand mpiCommand;
  const auto mpi = MakeMpiApp(&mpiCommand, "test");
  std::vector<std::string> render, mpiRender;
  for (const std::string& n : OptionNames(*app))
    if (n.rfind("render ", 0) == 0) render.push_back(n);
  for (const std::string& n : OptionNames(*mpi)) mpiRender.push_back(n);
  EXPECT_EQ(mpiRender, render);
  EXPECT_NE(MarkdownReference(*app, *mpi).find("## patchscan-mpi render\n"), std::string::npos);
  EXPECT_NE(ManPage(*app, *mpi, "test").find(".SH \"patchscan\\-mpi render FILE"), std::string::npos);
}

TEST(Reference, ManPageIsRoff) {
  Commands commands;
  const auto app = MakeApp(&commands, "9.9.9");
  RenderCommand mpiCommand;
  const auto mpi = MakeMpiApp(&mpiCommand, "9.9.9");
  const std::string man = ManPage(*app, *mpi, "9.9.9");
  EXPECT_EQ(man.rfind(".TH PATCHSCAN 1 ", 0), 0u);
  EXPECT_NE(man.find("patchscan 9.9.9"), std::string::npos);
  for (const char* section : {".SH NAME\n", ".SH SYNOPSIS\n", ".SH DESCRIPTION\n", ".SH \"EXIT STATUS\"\n"})
    EXPECT_NE(man.find(section), std::string::npos) << section;
  // No line of text may begin with a period or quote (roff would take it for a request),
  // and a backslash is only ever an escape.
  std::size_t start = 0;
  while (start < man.size()) {
    const std::size_t end = man.find('\n', start);
    const std::string line = man.substr(start, end - start);
    if (!line.empty() && line[0] == '.') {
      EXPECT_TRUE(line.rfind(".TH", 0) == 0 || line.rfind(".SH", 0) == 0 || line.rfind(".TP", 0) == 0 ||
                  line.rfind(".B ", 0) == 0 || line == ".br" || line == ".PP")
          << line;
    }
    EXPECT_NE(line.rfind("'", 0), 0u) << line;
    if (end == std::string::npos) break;
    start = end + 1;
  }
}

}  // namespace
}  // namespace patchscan::cli
