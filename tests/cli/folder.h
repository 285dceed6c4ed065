// What the command-line tests share beside running the program: reading an image's pixels,
// and a folder of its own for a test.
#pragma once

#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "cli/run_program.h"

namespace {

// Every channel of every pixel of an image file, as stored (alpha not multiplied in; empty
// if it cannot be read).
std::vector<float> Pixels(const std::string& path) {
  OIIO::ImageSpec config;
  config.attribute("oiio:UnassociatedAlpha", 1);
  auto in = OIIO::ImageInput::open(path, &config);
  if (!in) return {};
  const OIIO::ImageSpec& spec = in->spec();
  std::vector<float> px(static_cast<std::size_t>(spec.width) * spec.height * spec.nchannels);
  if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, px.data())) return {};
  return px;
}

// A folder of its own for one test, removed after it.
struct Folder {
  explicit Folder(const std::string& name)
      : path(std::filesystem::temp_directory_path() / ("patchscan_" + name + "_" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~Folder() { std::filesystem::remove_all(path); }
  // Runs patchscan with `args` in the folder; its exit code (its stderr kept for Err).
  int Run(const std::string& args) {
    const Result r = Patchscan(args, "cd " + path.string() + " &&");
    err = r.err;
    return r.code;
  }
  const std::string& Err() const { return err; }
  std::filesystem::path path;
  std::string err;
};

}  // namespace
