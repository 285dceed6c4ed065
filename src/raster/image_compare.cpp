#include "raster/image_compare.h"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>

#include "raster/image_io.h"
#include "raster/srgb.h"

namespace patchscan::raster {

std::variant<ComparableImage, std::string> ReadComparable(const std::string& path) {
  // As stored: a straight-alpha file's colour is linearised before alpha multiplies it.
  const auto library = imageio::Get();
  if (const auto* why = std::get_if<std::string>(&library)) return path + ": " + *why;
  auto read = std::get<const imageio::Library*>(library)->Read(path, imageio::Library::kAllChannels,
                                                                /*unassociatedAlpha=*/true);
  if (const auto* why = std::get_if<std::string>(&read)) return path + ": cannot read: " + *why;
  const imageio::FileSpec& spec = std::get<imageio::Image>(read).spec;
  if (spec.width <= 0 || spec.height <= 0 || spec.channels <= 0) return path + ": empty image";
  if (spec.depth > 1) return path + ": volume images are not compared";
  const int nc = spec.channels;
  const std::size_t nPixels = static_cast<std::size_t>(spec.width) * static_cast<std::size_t>(spec.height);
  std::vector<float>& all = std::get<imageio::Image>(read).pixels;

  auto channel = [&](const char* name, int fallback) {
    for (int c = 0; c < nc; ++c)
      if (static_cast<std::size_t>(c) < spec.channelNames.size() && spec.channelNames[static_cast<std::size_t>(c)] == name) return c;
    return fallback;
  };
  auto copy = [&](int c, std::vector<float>& dst) {
    if (c < 0 || c >= nc) return;
    dst.resize(nPixels);
    for (std::size_t i = 0; i < nPixels; ++i) dst[i] = all[i * static_cast<std::size_t>(nc) + static_cast<std::size_t>(c)];
  };

  // Three channels interleaved into one array.
  auto copy3 = [&](int c0, int c1, int c2, std::vector<float>& dst) {
    dst.resize(nPixels * 3);
    for (std::size_t i = 0; i < nPixels; ++i) {
      const float* px = &all[i * static_cast<std::size_t>(nc)];
      dst[3 * i] = px[c0];
      dst[3 * i + 1] = px[c1];
      dst[3 * i + 2] = px[c2];
    }
  };

  // Linear light, premultiplied, as renders are: 8-bit sRGB files (PNG, JPEG) decoded
  // through the sRGB curve, straight alpha multiplied in.
  const bool srgb = spec.colorSpace == "sRGB";
  const bool straight = spec.unassociatedAlpha;
  const int alphaChannel = channel("A", spec.alphaChannel);
  if (srgb || straight)
    for (std::size_t i = 0; i < nPixels; ++i) {
      float* px = &all[i * static_cast<std::size_t>(nc)];
      const float a = straight && alphaChannel >= 0 && alphaChannel < nc ? px[alphaChannel] : 1.0f;
      for (int c = 0; c < std::min(nc, 3); ++c) {
        if (c == alphaChannel) continue;
        px[c] = a * (srgb ? static_cast<float>(LinearFromSrgb(px[c])) : px[c]);
      }
    }

  ComparableImage img;
  img.width = spec.width;
  img.height = spec.height;
  // Colour: R, G, B by name, else the first three channels (a grey image in all three).
  copy3(channel("R", 0), channel("G", nc >= 3 ? 1 : 0), channel("B", nc >= 3 ? 2 : 0), img.rgb);
  copy(channel("A", spec.alphaChannel), img.alpha);
  copy(channel("Z", spec.zChannel), img.z);
  const int nx = channel("N.x", -1), ny = channel("N.y", -1), nz = channel("N.z", -1);
  if (nx >= 0 && ny >= 0 && nz >= 0) copy3(nx, ny, nz, img.normal);
  copy(channel("id", -1), img.id);
  return img;
}

CoverageContour CoverageEdges(const std::vector<float>& alpha, int width, int height) {
  // Inside: alpha ≥ 1/2. A box-filtered coverage of a straight edge crosses 1/2 at the
  // edge itself, so linear interpolation between pixel centres places the contour within
  // a fraction of a pixel of the true edge.
  // Beyond the frame the nearest pixel's coverage continues: the frame's own border is no
  // coverage edge (a full-frame background has none at all), and a surface cut by the
  // frame has its contour end there.
  constexpr double kLevel = 0.5;
  auto at = [&](int x, int y) -> double {
    x = std::clamp(x, 0, width - 1);
    y = std::clamp(y, 0, height - 1);
    return alpha[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) + static_cast<std::size_t>(x)];
  };
  CoverageContour c;
  for (int cy = -1; cy < height; ++cy) {
    for (int cx = -1; cx < width; ++cx) {
      // Corners c0..c3 clockwise from the top left; edge k runs from corner k to k+1.
      const int xs[4] = {cx, cx + 1, cx + 1, cx}, ys[4] = {cy, cy, cy + 1, cy + 1};
      double v[4];
      int mask = 0;
      for (int k = 0; k < 4; ++k) {
        v[k] = at(xs[k], ys[k]);
        if (v[k] >= kLevel) mask |= 1 << k;
      }
      if (mask == 0 || mask == 15) continue;
      Vec2 cross[4];
      bool crossed[4];
      for (int k = 0; k < 4; ++k) {
        const int l = (k + 1) % 4;
        crossed[k] = ((mask >> k) & 1) != ((mask >> l) & 1);
        if (!crossed[k]) continue;
        const double t = (kLevel - v[k]) / (v[l] - v[k]);
        cross[k] = Vec2(xs[k] + 0.5 + t * (xs[l] - xs[k]), ys[k] + 0.5 + t * (ys[l] - ys[k]));
      }
      auto add = [&](int e, int f) {
        c.from.push_back(cross[e]);
        c.to.push_back(cross[f]);
      };
      if (mask == 5 || mask == 10) {
        // A saddle cell: the centre's value says whether the inside corners connect.
        const bool centreInside = (v[0] + v[1] + v[2] + v[3]) / 4 >= kLevel;
        // Corners 0 and 2 inside (mask 5) with the centre inside: cut off corners 1 and 3.
        if ((mask == 5) == centreInside) {
          add(0, 1);
          add(2, 3);
        } else {
          add(3, 0);
          add(1, 2);
        }
        continue;
      }
      int e[2], n = 0;
      for (int k = 0; k < 4; ++k)
        if (crossed[k]) e[n++] = k;
      add(e[0], e[1]);
    }
  }
  return c;
}

namespace {

double DistanceToSegment(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 d = b - a;
  const double len2 = d.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * d)).norm();
}

}  // namespace

std::vector<double> DistancesToContour(const CoverageContour& a, const CoverageContour& b, int width,
                                       int height) {
  std::vector<double> out;
  if (b.from.empty()) return out;
  // Each segment of b lies in one marching-squares cell (cx, cy) ∈ [-1, width) × [-1, height):
  // bucket them by cell (compressed rows).
  const int cw = width + 1, ch = height + 1;
  auto cellOf = [&](const Vec2& p, int& x, int& y) {
    x = std::clamp(static_cast<int>(std::floor(p.x() - 0.5)), -1, width - 1) + 1;
    y = std::clamp(static_cast<int>(std::floor(p.y() - 0.5)), -1, height - 1) + 1;
  };
  std::vector<int> start(static_cast<std::size_t>(cw) * static_cast<std::size_t>(ch) + 1, 0), seg(b.from.size());
  std::vector<int> cellIndex(b.from.size());
  for (std::size_t s = 0; s < b.from.size(); ++s) {
    int x, y;
    cellOf(0.5 * (b.from[s] + b.to[s]), x, y);
    cellIndex[s] = y * cw + x;
    ++start[static_cast<std::size_t>(cellIndex[s]) + 1];
  }
  for (std::size_t i = 1; i < start.size(); ++i) start[i] += start[i - 1];
  std::vector<int> fill(start.begin(), start.end() - 1);
  for (std::size_t s = 0; s < b.from.size(); ++s) seg[static_cast<std::size_t>(fill[static_cast<std::size_t>(cellIndex[s])]++)] = static_cast<int>(s);

  auto nearest = [&](const Vec2& p) {
    int px, py;
    cellOf(p, px, py);
    double best = std::numeric_limits<double>::infinity();
    const int rMax = std::max(cw, ch);
    for (int r = 0; r <= rMax; ++r) {
      for (int y = py - r; y <= py + r; ++y) {
        if (y < 0 || y >= ch) continue;
        const bool rowEdge = (y == py - r || y == py + r);
        for (int x = px - r; x <= px + r; x += (rowEdge ? 1 : 2 * r)) {
          if (x >= 0 && x < cw) {
            const std::size_t cell = static_cast<std::size_t>(y) * static_cast<std::size_t>(cw) + static_cast<std::size_t>(x);
            for (int k = start[cell]; k < start[cell + 1]; ++k) {
              const std::size_t s = static_cast<std::size_t>(seg[static_cast<std::size_t>(k)]);
              best = std::min(best, DistanceToSegment(p, b.from[s], b.to[s]));
            }
          }
          if (r == 0) break;
        }
      }
      // Cells of ring r + 1 lie at least r pixels from p (cells are one pixel wide).
      if (best <= r) break;
    }
    return best;
  };
  out.reserve(2 * a.from.size());
  for (std::size_t s = 0; s < a.from.size(); ++s) {
    out.push_back(nearest(a.from[s]));
    out.push_back(nearest(a.to[s]));
  }
  return out;
}

ErrorStats Summarize(std::vector<double> errors) {
  ErrorStats s;
  s.count = static_cast<long>(errors.size());
  if (errors.empty()) return s;
  double sum = 0;
  for (double e : errors) {
    s.max = std::max(s.max, e);
    sum += e;
  }
  s.mean = sum / static_cast<double>(errors.size());
  // Nearest rank: the smallest error at or above 99% of the set.
  const std::size_t k = static_cast<std::size_t>(std::ceil(0.99 * static_cast<double>(errors.size()))) - 1;
  std::nth_element(errors.begin(), errors.begin() + static_cast<std::ptrdiff_t>(k), errors.end());
  s.p99 = errors[k];
  return s;
}

ImageComparison CompareImages(const ComparableImage& a, const ComparableImage& b) {
  ImageComparison r;
  const std::size_t n = static_cast<std::size_t>(a.width) * static_cast<std::size_t>(a.height);

  // Coverage edges, both ways.
  if (!a.alpha.empty() && !b.alpha.empty()) {
    for (std::size_t i = 0; i < n; ++i) {
      const double d = std::abs(static_cast<double>(a.alpha[i]) - b.alpha[i]);
      r.coverageAreaDifference += d;
      if (d > 0.5) ++r.pixelsCoverageDiffers;
    }
    const CoverageContour ca = CoverageEdges(a.alpha, a.width, a.height);
    const CoverageContour cb = CoverageEdges(b.alpha, b.width, b.height);
    if (ca.from.empty() != cb.from.empty()) {
      r.silhouetteMissing = true;
    } else if (!ca.from.empty()) {
      std::vector<double> d = DistancesToContour(ca, cb, a.width, a.height);
      const std::vector<double> back = DistancesToContour(cb, ca, a.width, a.height);
      // Where the largest is: end points of a's segments, then of b's, in order.
      std::size_t worst = 0;
      for (std::size_t k = 0; k < d.size() + back.size(); ++k)
        if ((k < d.size() ? d[k] : back[k - d.size()]) > (worst < d.size() ? d[worst] : back[worst - d.size()])) worst = k;
      const CoverageContour& on = worst < d.size() ? ca : cb;
      const std::size_t k = worst < d.size() ? worst : worst - d.size();
      r.silhouetteWorst = k % 2 == 0 ? on.from[k / 2] : on.to[k / 2];
      r.silhouetteWorstInA = worst < d.size();
      d.insert(d.end(), back.begin(), back.end());
      r.silhouette = Summarize(std::move(d));
    } else {
      r.noContours = true;
    }
  }

  // Depth and normals where both see the same surface over the whole pixel.
  const bool haveZ = !a.z.empty() && !b.z.empty(), haveN = !a.normal.empty() && !b.normal.empty();
  if ((haveZ || haveN) && !a.alpha.empty() && !b.alpha.empty()) {
    const bool haveId = !a.id.empty() && !b.id.empty();
    std::vector<double> dz, dn;
    for (std::size_t i = 0; i < n; ++i) {
      if (a.alpha[i] < 1.0f || b.alpha[i] < 1.0f) continue;
      if (haveId && a.id[i] != b.id[i]) continue;
      if (haveZ && a.z[i] > 0 && b.z[i] > 0)
        dz.push_back(std::abs(static_cast<double>(a.z[i]) - b.z[i]) / b.z[i]);
      if (haveN) {
        const Eigen::Vector3d na(a.normal[3 * i], a.normal[3 * i + 1], a.normal[3 * i + 2]);
        const Eigen::Vector3d nb(b.normal[3 * i], b.normal[3 * i + 1], b.normal[3 * i + 2]);
        if (na.squaredNorm() > 0 && nb.squaredNorm() > 0)
          dn.push_back(std::atan2(na.cross(nb).norm(), na.dot(nb)) * 180.0 / M_PI);
      }
    }
    if (haveZ) r.depth = Summarize(std::move(dz));
    if (haveN) r.normalDegrees = Summarize(std::move(dn));
  }

  // Colour.
  double sumSq = 0;
  std::size_t worst = 0;
  for (std::size_t i = 0; i < 3 * n; ++i) {
    const double d = static_cast<double>(a.rgb[i]) - b.rgb[i];
    sumSq += d * d;
    if (std::abs(d) > r.maxColourDifference) {
      r.maxColourDifference = std::abs(d);
      worst = i / 3;
    }
  }
  if (n > 0) {
    r.colourWorstX = static_cast<int>(worst % static_cast<std::size_t>(a.width));
    r.colourWorstY = static_cast<int>(worst / static_cast<std::size_t>(a.width));
    for (int c = 0; c < 3; ++c) {
      r.colourWorstA[c] = a.rgb[3 * worst + static_cast<std::size_t>(c)];
      r.colourWorstB[c] = b.rgb[3 * worst + static_cast<std::size_t>(c)];
    }
    // The region around it: pixels within kWorstRegionPx differing by more than half as much.
    const double half = 0.5 * r.maxColourDifference;
    int x0 = r.colourWorstX, x1 = x0, y0 = r.colourWorstY, y1 = y0;
    for (int y = std::max(0, y0 - kWorstRegionPx); y <= std::min(a.height - 1, r.colourWorstY + kWorstRegionPx); ++y)
      for (int x = std::max(0, r.colourWorstX - kWorstRegionPx); x <= std::min(a.width - 1, r.colourWorstX + kWorstRegionPx);
           ++x) {
        const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(a.width) + static_cast<std::size_t>(x);
        double d = 0;
        for (std::size_t c = 0; c < 3; ++c) d = std::max(d, std::abs(static_cast<double>(a.rgb[3 * i + c]) - b.rgb[3 * i + c]));
        if (half > 0 && d > half) {
          ++r.colourWorstRegionPixels;
          x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
        }
      }
    r.colourWorstRegion = {x0, y0, x1, y1};
  }
  r.rmse = n > 0 ? std::sqrt(sumSq / (3.0 * static_cast<double>(n))) : 0.0;
  r.psnr = r.rmse > 0 ? 20.0 * std::log10(1.0 / r.rmse) : std::numeric_limits<double>::infinity();
  return r;
}

}  // namespace patchscan::raster
