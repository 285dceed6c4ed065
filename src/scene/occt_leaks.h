// Open CASCADE's one-time allocations, which LeakSanitizer is told to expect.
#pragma once

#if defined(__has_feature)
#if __has_feature(address_sanitizer)
#define PATCHSCAN_ADDRESS_SANITIZER 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(PATCHSCAN_ADDRESS_SANITIZER)
// LeakSanitizer's suppressions for a build under the sanitizers. LeakSanitizer looks for
// them in the program, not in the module that reads CAD files: the CAD module's loader
// (cad_library.cpp) and the reader (cad_reader.cpp, which tests link without the loader)
// each define them, weak, so that a program linking both has one. Open CASCADE's data
// exchange registers its controllers, editors and static parameters once per process, on
// the first reader or writer made, and never frees them; its XDE application and driver
// table are process-wide singletons; its STEP writer (the tests' models) leaves its default
// axis in a reference cycle. Only these are named: a reader, document or shape that
// outlives its use is still reported. OCCT is built without frame pointers: the names show in
// a leak's stack with ASAN_OPTIONS=fast_unwind_on_malloc=0 (tests/CMakeLists.txt, .ci/fuzz).
extern "C" __attribute__((weak)) const char* __lsan_default_suppressions() {
  return "leak:STEPControl_Controller::Init\n"
         "leak:STEPCAFControl_Controller::Init\n"
         "leak:IGESControl_Controller::Init\n"
         "leak:IGESCAFControl_Controller::Init\n"
         "leak:XSAlgo::Init\n"
         "leak:XCAFApp_Application::GetApplication\n"
         "leak:TPrsStd_DriverTable::Get\n"
         "leak:STEPConstruct_ContextTool::GetDefaultAxis\n";
}
#endif
