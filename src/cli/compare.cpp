#include "cli/compare.h"

#include <cmath>
#include <fstream>
#include <sstream>
#include <ostream>

#include "cli/checks.h"
#include "raster/image_compare.h"
#include "raster/image_writer.h"

namespace patchscan::cli {

CLI::App* AddCompareCommand(CLI::App* app, CompareOptions* o) {
  CLI::App* cmd = app->add_subcommand(
      "compare",
      "Measure how far image A is from the reference image B (same size): coverage edges "
      "(the alpha = 1/2 contours, distances both ways, in pixels: maximum and 99th percentile), "
      "pixels whose coverage differs by more than 1/2, relative depth error and normal angle "
      "where both images see the same surface over the whole pixel (from the Z, N.x N.y N.z "
      "and id channels of 'render --aov' EXR files), and colour RMSE and PSNR, in linear light "
      "(8-bit sRGB files are decoded through the sRGB curve, straight alpha multiplied in). "
      "Measures an "
      "image cannot give (no alpha, no Z) are reported as not measured. Exit codes: 0 every "
      "measure within its warning threshold, 1 a warning, 2 a failure, 3 the images differ "
      "in size, 4 an image could not be read or written, 64 a bad command line (as for every command).");
  cmd->add_option("A", o->a, "the image to measure")->type_name("IMAGE")->required();
  cmd->add_option("B", o->b, "the reference image")->type_name("IMAGE")->required();
  cmd->add_option("--diff", o->diff,
                  "write |A - B| of the colour, times --diff-scale, to this image (alpha 1)")
      ->type_name("IMAGE");
  cmd->add_option("--diff-scale", o->diffScale, "scale of the difference image")
      ->type_name("K")
      ->check(Positive())
      ->capture_default_str();
  cmd->add_option("--json", o->json, "also write the measures as JSON to this file")->type_name("FILE");
  auto threshold = [&](const char* name, double* value, const char* what) {
    // The unit of the measure: pixels, degrees, or a plain number.
    const std::string n = name;
    const char* unit = n.find("silhouette") != std::string::npos ? "PX" : n.find("normal") != std::string::npos ? "DEG" : "X";
    cmd->add_option(name, *value, what)->type_name(unit)->check(NonNegative())->capture_default_str();
  };
  threshold("--warn-silhouette", &o->warn.silhouettePx, "warn above this maximum coverage-edge distance, pixels");
  threshold("--fail-silhouette", &o->fail.silhouettePx, "fail above this maximum coverage-edge distance, pixels");
  threshold("--warn-rmse", &o->warn.rmse, "warn above this colour RMSE");
  threshold("--fail-rmse", &o->fail.rmse, "fail above this colour RMSE");
  threshold("--warn-depth", &o->warn.depth, "warn above this 99th percentile relative depth error");
  threshold("--fail-depth", &o->fail.depth, "fail above this 99th percentile relative depth error");
  threshold("--warn-normal", &o->warn.normalDeg, "warn above this 99th percentile normal angle, degrees");
  threshold("--fail-normal", &o->fail.normalDeg, "fail above this 99th percentile normal angle, degrees");
  return cmd;
}

namespace {

void PrintStats(std::ostream& out, const char* name, const std::optional<raster::ErrorStats>& s,
                const char* unit, const char* why) {
  out << name << ": ";
  if (!s) {
    out << "not measured (" << why << ")\n";
    return;
  }
  if (s->count == 0) {
    out << "no pixel to compare\n";
    return;
  }
  out << "max " << s->max << unit << ", p99 " << s->p99 << unit << ", mean " << s->mean << unit << " ("
      << s->count << (std::string(name) == "coverage edges" ? " edge points)\n" : " pixels)\n");
}

void JsonStats(std::ostream& js, const char* name, const std::optional<raster::ErrorStats>& s) {
  js << '"' << name << "\": ";
  if (!s || s->count == 0) {
    js << "null";
    return;
  }
  js << "{\"max\": " << s->max << ", \"p99\": " << s->p99 << ", \"mean\": " << s->mean << ", \"count\": " << s->count
     << '}';
}

// The image of |a - b| * scale, alpha 1, through the all-or-nothing writer.
std::optional<std::string> WriteDifference(const raster::ComparableImage& a, const raster::ComparableImage& b,
                                           double scale, const std::string& path) {
  auto opened = raster::ImageWriter::Open(path, a.width, a.height);
  if (auto* msg = std::get_if<std::string>(&opened)) return *msg;
  auto& writer = *std::get<std::unique_ptr<raster::ImageWriter>>(opened);
  std::vector<float> row(static_cast<std::size_t>(a.width) * raster::kChannels, 0.0f);
  for (int y = 0; y < a.height; ++y) {
    for (int x = 0; x < a.width; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(a.width) + static_cast<std::size_t>(x);
      float* px = &row[static_cast<std::size_t>(x) * raster::kChannels];
      for (int c = 0; c < 3; ++c)
        px[c] = static_cast<float>(std::abs(static_cast<double>(a.rgb[3 * i + static_cast<std::size_t>(c)]) -
                                            b.rgb[3 * i + static_cast<std::size_t>(c)]) * scale);
      px[3] = 1.0f;
    }
    if (!writer.WriteRow(y, row.data())) return path + ": cannot write";
  }
  const auto committed = writer.Commit();
  if (const auto* msg = std::get_if<std::string>(&committed)) return *msg;
  return std::nullopt;
}

}  // namespace

int RunCompare(const CompareOptions& o, std::ostream& out, std::ostream& err) {
  auto ra = raster::ReadComparable(o.a);
  if (auto* msg = std::get_if<std::string>(&ra)) {
    err << "patchscan: " << *msg << '\n';
    return kCompareFileError;
  }
  auto rb = raster::ReadComparable(o.b);
  if (auto* msg = std::get_if<std::string>(&rb)) {
    err << "patchscan: " << *msg << '\n';
    return kCompareFileError;
  }
  const raster::ComparableImage& a = std::get<raster::ComparableImage>(ra);
  const raster::ComparableImage& b = std::get<raster::ComparableImage>(rb);
  if (a.width != b.width || a.height != b.height) {
    err << "patchscan: " << o.a << " is " << a.width << "x" << a.height << ", " << o.b << " is " << b.width << "x"
        << b.height << ": different sizes\n";
    return kCompareDifferentSize;
  }
  const raster::ImageComparison c = raster::CompareImages(a, b);

  const bool alpha = !a.alpha.empty() && !b.alpha.empty();
  out << "compare " << o.a << " against " << o.b << " (" << a.width << "x" << a.height << ")\n";
  if (c.silhouetteMissing)
    out << "coverage edges: one image has none, the other some\n";
  else
    PrintStats(out, "coverage edges", c.silhouette, " px",
               !alpha        ? "no alpha channel in both"
               : c.noContours ? "no coverage edge in either image: each covers the whole frame or none of it; "
                                "compare colour, or render without the background"
                              : "neither image covers anything partly");
  if (c.silhouette && c.silhouette->count > 0 && c.silhouette->max > 0)
    out << "  farthest at (" << c.silhouetteWorst.x() << ", " << c.silhouetteWorst.y() << ") on the edge of "
        << (c.silhouetteWorstInA ? o.a : o.b) << '\n';
  if (alpha)
    out << "coverage: " << c.pixelsCoverageDiffers << " pixels differ by more than 1/2, area difference "
        << c.coverageAreaDifference << " px\n";
  PrintStats(out, "depth (relative)", c.depth, "", "needs A, Z and id channels in both");
  PrintStats(out, "normal angle", c.normalDegrees, " deg", "needs A and N.x N.y N.z channels in both");
  out << "colour: RMSE " << c.rmse << ", PSNR " << c.psnr << " dB, max difference " << c.maxColourDifference << '\n';
  if (c.maxColourDifference > 0) {
    auto rgb = [](const std::array<double, 3>& v) {
      std::ostringstream s;
      s << v[0] << ' ' << v[1] << ' ' << v[2];
      return s.str();
    };
    const auto& box = c.colourWorstRegion;
    out << "  largest at pixel (" << c.colourWorstX << ", " << c.colourWorstY << "): A " << rgb(c.colourWorstA) << ", B "
        << rgb(c.colourWorstB) << "; within " << raster::kWorstRegionPx << " px of it " << c.colourWorstRegionPixels
        << " pixels differ by more than half as much, in x " << box[0] << ".." << box[2] << ", y " << box[1] << ".."
        << box[3] << '\n';
  }

  // The verdict: every measured quantity against its thresholds.
  int code = kCompareOk;
  auto check = [&](const char* what, bool measured, double value, double warn, double fail) {
    if (!measured) return;
    if (value > fail) {
      out << "FAIL: " << what << ' ' << value << " > " << fail << '\n';
      code = std::max(code, kCompareFailure);
    } else if (value > warn) {
      out << "WARNING: " << what << ' ' << value << " > " << warn << '\n';
      code = std::max(code, kCompareWarning);
    }
  };
  if (c.silhouetteMissing) {
    out << "FAIL: coverage edges in one image only\n";
    code = kCompareFailure;
  }
  const bool sil = c.silhouette && c.silhouette->count > 0;
  check("coverage-edge distance", sil, sil ? c.silhouette->max : 0, o.warn.silhouettePx, o.fail.silhouettePx);
  check("colour RMSE", true, c.rmse, o.warn.rmse, o.fail.rmse);
  const bool dep = c.depth && c.depth->count > 0, nrm = c.normalDegrees && c.normalDegrees->count > 0;
  check("p99 relative depth error", dep, dep ? c.depth->p99 : 0, o.warn.depth, o.fail.depth);
  check("p99 normal angle", nrm, nrm ? c.normalDegrees->p99 : 0, o.warn.normalDeg, o.fail.normalDeg);
  if (code == kCompareOk) out << "PASS\n";

  if (!o.diff.empty()) {
    if (auto msg = WriteDifference(a, b, o.diffScale, o.diff)) {
      err << "patchscan: " << *msg << '\n';
      return kCompareFileError;
    }
  }
  if (!o.json.empty()) {
    std::ofstream js(o.json);
    js << "{\"width\": " << a.width << ", \"height\": " << a.height << ", ";
    JsonStats(js, "silhouette_px", c.silhouette);
    js << ", \"silhouette_missing\": " << (c.silhouetteMissing ? "true" : "false")
       << ", \"pixels_coverage_differs\": " << c.pixelsCoverageDiffers
       << ", \"coverage_area_difference\": " << c.coverageAreaDifference << ", ";
    JsonStats(js, "depth_relative", c.depth);
    js << ", ";
    JsonStats(js, "normal_degrees", c.normalDegrees);
    js << ", \"rmse\": " << c.rmse << ", \"psnr\": " << (std::isfinite(c.psnr) ? std::to_string(c.psnr) : "null")
       << ", \"max_colour_difference\": " << c.maxColourDifference << ", \"max_colour_difference_at\": [" << c.colourWorstX
       << ", " << c.colourWorstY << "], \"verdict\": " << code << "}\n";
    if (!js) {
      err << "patchscan: " << o.json << ": cannot write\n";
      return kCompareFileError;
    }
  }
  return code;
}

}  // namespace patchscan::cli
