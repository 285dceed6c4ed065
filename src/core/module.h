// Modules loaded on first use: a library whose dependencies are costly to load (OpenImageIO's
// 260 shared libraries, Open CASCADE's 60) lives in a module of its own that a run loads
// only when it needs it (raster/image_io.h, scene/cad_library.h). A module has one entry
// point, a C function that takes the interface its caller was built with and returns the
// module's implementation of it, or null when the module was built with another.
#pragma once

#include <dlfcn.h>

#include <filesystem>
#include <string>
#include <system_error>
#include <variant>
#include <vector>

namespace patchscan {

// Where a module may be, in order: the file `name` in `fromBindir` relative to the running
// program's directory (an installation moved elsewhere), in the installation's directory
// `installed`, then in the build tree's `built`.
struct ModulePlaces {
  const char* name;
  const char* fromBindir;
  const char* installed;
  const char* built;
};

// The first of `places` that loads and answers `entry(interface)` with non-null, cast to
// `Interface`; else the reasons, one place a line ("" when none exists). Never closed: the
// module's objects live until the process ends.
template <class Interface>
std::variant<const Interface*, std::string> LoadModule(const ModulePlaces& places, const char* entry,
                                                       const char* interface) {
  std::vector<std::filesystem::path> candidates;
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) candidates.push_back(self.parent_path() / places.fromBindir / places.name);
  candidates.push_back(std::filesystem::path(places.installed) / places.name);
  candidates.push_back(std::filesystem::path(places.built) / places.name);
  std::string tried;
  for (const std::filesystem::path& place : candidates) {
    if (!std::filesystem::exists(place, ec)) continue;
    void* handle = ::dlopen(place.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!handle) {
      const char* why = ::dlerror();
      tried += std::string("\n  ") + (why ? why : place.string());
      continue;
    }
    using Entry = const Interface* (*)(const char*);
    auto function = reinterpret_cast<Entry>(::dlsym(handle, entry));
    if (const Interface* module = function ? function(interface) : nullptr) return module;
    tried += "\n  " + place.string() + ": built from another version of patchscan";
  }
  return tried;
}

}  // namespace patchscan
