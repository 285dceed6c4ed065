#include "scene/obj_reader.h"

#include <charconv>
#include <cmath>
#include <map>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "scene/text_file.h"

namespace patchscan {

namespace {

// A statement's kind, as a warning names it, is cut to this many characters.
constexpr std::size_t kKindChars = 48;

// The statements of a line, its words split at blanks and tabs.
std::vector<std::string_view> Words(std::string_view line) {
  std::vector<std::string_view> w;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) w.push_back(line.substr(start, i - start));
  }
  return w;
}

class ObjParser {
 public:
  ObjParser(std::string_view text, std::string name, const ObjOptions& options)
      : text_(text), name_(std::move(name)) {
    mesh_.scheme = options.scheme;
    mesh_.interpolateBoundary = 1;
  }

  std::variant<Scene, SourceError> Parse() {
    // Step 1: the statements, line by line ('\' at the end of a line continues it).
    std::size_t pos = 0;
    int lineNo = 0;
    while (pos < text_.size() && !error_) {
      ++lineNo;
      const int first = lineNo;
      std::string joined;
      std::string_view line;
      for (;;) {
        const std::size_t end = std::min(text_.find('\n', pos), text_.size());
        std::string_view piece = text_.substr(pos, end - pos);
        pos = end + 1;
        if (!piece.empty() && piece.back() == '\r') piece.remove_suffix(1);
        if (!piece.empty() && piece.back() == '\\' && pos < text_.size()) {
          joined.append(piece.substr(0, piece.size() - 1)).push_back(' ');
          ++lineNo;
          continue;
        }
        if (joined.empty()) {
          line = piece;
        } else {
          joined.append(piece);
          line = joined;
        }
        break;
      }
      if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
      Statement(Words(line), first);
    }
    if (error_) return *error_;
    if (mesh_.faceSizes.empty()) {
      std::string skipped;
      for (const auto& [kind, seen] : skipped_)
        skipped += (skipped.empty() ? "" : ", ") + std::to_string(seen.second) + " '" + kind + "'";
      return SourceError{name_, 0, "no faces ('f') to render" + (skipped.empty() ? "" : " (not read here: " + skipped + ")")};
    }
    for (const auto& [kind, seen] : skipped_)
      scene_.warnings.push_back(name_ + ":" + std::to_string(seen.first) + ": '" + kind + "' is not read here: " +
                                std::to_string(seen.second) + (seen.second == 1 ? " statement" : " statements") +
                                " skipped");
    // Texture coordinates apply when every face gives them.
    if (!mesh_.stIndices.empty() && mesh_.stIndices.size() != mesh_.faceVertices.size()) {
      scene_.warnings.push_back(name_ + ":" + std::to_string(firstFaceWithoutTexCoords_) +
                                ": this face gives no texture coordinates (v/vt) and others do: they are not applied, "
                                "textures use each face's own (u, v)");
      mesh_.stIndices.clear();
    }
    if (mesh_.stIndices.empty()) mesh_.st.clear();
    for (const auto& [face, line] : holes_) {
      if (face >= static_cast<int>(mesh_.faceSizes.size()))
        return SourceError{name_, line, "tag \"hole\": face " + std::to_string(face) + " is out of range (" +
                                            std::to_string(mesh_.faceSizes.size()) + " faces, from 0)"};
      mesh_.holes.push_back(face);
    }

    // Step 2: the cage, every rendered face a surface.
    std::vector<SubdivFace> faces;
    SceneCage cage{name_, faceLines_.front(), mesh_.scheme, {}};
    try {
      faces = PrepareSubdivFaces(mesh_, &cage.counts);
    } catch (const std::invalid_argument& e) {
      return SourceError{name_, faceLines_.front(), std::string("the cage: ") + e.what()};
    }
    scene_.source = name_;
    scene_.cages.push_back(cage);
    scene_.ReserveSurfaces(faces.size(), false);  // an .obj has no appearances
    for (SubdivFace& f : faces) {
      scene_.sourceLines.push_back(faceLines_[static_cast<std::size_t>(f.Face())]);
      scene_.sourceFiles.push_back(name_);
      scene_.surfaces.push_back(Surface{std::move(f), Affine3::Identity()});
    }
    return std::move(scene_);
  }

 private:
  bool Fail(int line, std::string message) {
    if (!error_) error_ = SourceError{name_, line, std::move(message)};
    return false;
  }

  bool Number(std::string_view w, int line, double* out) {
    const auto n = ParseNumber(w);
    if (!n) return Fail(line, "expected a number, found " + Shown(w));
    if (!n->finite) return Fail(line, "the number " + Shown(w) + " is not finite");
    *out = n->value;
    return true;
  }

  bool Whole(std::string_view w, int line, long long* out) {
    const char* end = w.data() + w.size();
    const auto r = std::from_chars(w.data() + (!w.empty() && w[0] == '+' ? 1 : 0), end, *out);
    if (r.ec != std::errc() || r.ptr != end) return Fail(line, "expected a whole number, found " + Shown(w));
    return true;
  }

  // An OBJ index (1-based, or negative: from the end of the `count` read so far) as 0-based.
  bool Index(std::string_view w, std::size_t count, const char* what, const char* whats, int line, int* out) {
    long long k = 0;
    if (!Whole(w, line, &k)) return false;
    const long long n = static_cast<long long>(count);
    const long long zeroBased = k > 0 ? k - 1 : n + k;
    if (k == 0 || zeroBased < 0 || zeroBased >= n)
      return Fail(line, std::string(what) + " index " + Shown(w) + " is out of range (" + std::to_string(count) + " " +
                            (count == 1 ? what : whats) + " read so far)");
    *out = static_cast<int>(zeroBased);
    return true;
  }

  void Statement(const std::vector<std::string_view>& w, int line) {
    if (w.empty()) return;
    const std::string_view k = w[0];
    if (k == "v") {
      if (w.size() < 4 || w.size() > 5) {
        Fail(line, "'v' takes x y z [w]");
        return;
      }
      Vec3 p;
      double weight = 1.0;
      for (int i = 0; i < 3; ++i)
        if (!Number(w[static_cast<std::size_t>(i) + 1], line, &p[i])) return;
      if (w.size() == 5 && !Number(w[4], line, &weight)) return;
      mesh_.points.push_back(p);
    } else if (k == "vt" || k == "vn") {
      const bool vt = k == "vt";
      if (vt ? (w.size() < 2 || w.size() > 4) : w.size() != 4) {
        Fail(line, vt ? "'vt' takes u [v [w]]" : "'vn' takes x y z");
        return;
      }
      double x[3] = {0.0, 0.0, 0.0};
      for (std::size_t i = 1; i < w.size(); ++i)
        if (!Number(w[i], line, &x[i - 1])) return;
      // OBJ's v runs up the image, RenderMan's t down it.
      if (vt) mesh_.st.emplace_back(x[0], 1.0 - x[1]);
      if (!vt) ++normals_;
    } else if (k == "f") {
      Face(w, line);
    } else if (k == "t") {
      Tag(w, line);
    } else if (k == "g" || k == "o" || k == "s" || k == "usemtl" || k == "mtllib") {
      // Grouping, smoothing groups and materials: nothing to render.
    } else {
      auto [it, inserted] = skipped_.try_emplace(std::string(k.substr(0, kKindChars)), line, 0);
      ++it->second.second;
    }
  }

  void Face(const std::vector<std::string_view>& w, int line) {
    const int n = static_cast<int>(w.size()) - 1;
    if (n < 3) {
      Fail(line, "a face has at least 3 vertices, this one " + std::to_string(n));
      return;
    }
    if (mesh_.scheme == SubdivScheme::Loop && n != 3) {
      Fail(line, "a face of " + std::to_string(n) + " vertices: a Loop cage is of triangles");
      return;
    }
    const std::size_t start = mesh_.faceVertices.size();
    std::vector<int> faceStIndices;
    for (int i = 1; i <= n; ++i) {
      // v, v/vt, v//vn or v/vt/vn
      const std::string_view ref = w[static_cast<std::size_t>(i)];
      const std::size_t s1 = ref.find('/');
      int v = 0, vt = 0, unused = 0;
      if (!Index(ref.substr(0, s1), mesh_.points.size(), "vertex", "vertices", line, &v)) return;
      bool hasVt = false;
      if (s1 != std::string_view::npos) {
        const std::string_view rest = ref.substr(s1 + 1);
        const std::size_t s2 = rest.find('/');
        const std::string_view t = rest.substr(0, s2);
        if (!t.empty() && !Index(t, mesh_.st.size(), "texture coordinate", "texture coordinates", line, &vt)) return;
        hasVt = !t.empty();
        if (s2 != std::string_view::npos && !Index(rest.substr(s2 + 1), normals_, "normal", "normals", line, &unused)) return;
        if (t.empty() && s2 == std::string_view::npos) {
          Fail(line, "a face vertex " + Shown(ref) + " is v, v/vt, v//vn or v/vt/vn");
          return;
        }
      }
      for (std::size_t j = start; j < mesh_.faceVertices.size(); ++j)
        if (mesh_.faceVertices[j] == v) {
          Fail(line, "the face uses vertex " + std::to_string(v + 1) + " twice (a degenerate face)");
          return;
        }
      mesh_.faceVertices.push_back(v);
      if (hasVt) faceStIndices.push_back(vt);
    }
    // A face's texture coordinates are all given or none.
    if (!faceStIndices.empty() && static_cast<int>(faceStIndices.size()) != n) {
      Fail(line, "a face gives texture coordinates (v/vt) at some of its vertices only");
      return;
    }
    if (faceStIndices.empty() && firstFaceWithoutTexCoords_ == 0) firstFaceWithoutTexCoords_ = line;
    mesh_.stIndices.insert(mesh_.stIndices.end(), faceStIndices.begin(), faceStIndices.end());
    mesh_.faceSizes.push_back(n);
    faceLines_.push_back(line);
  }

  // t name nint/nfloat/nstring ints... floats... strings...
  void Tag(const std::vector<std::string_view>& w, int line) {
    if (w.size() < 3) {
      Fail(line, "a tag line is 't name nint/nfloat/nstring arguments...'");
      return;
    }
    const std::string_view name = w[1];
    long long counts[3] = {0, 0, 0};
    std::string_view c = w[2];
    for (int i = 0; i < 3; ++i) {
      const std::size_t slash = c.find('/');
      if ((i < 2) == (slash == std::string_view::npos)) {
        Fail(line, "tag " + Shown(name) + ": the counts " + Shown(w[2]) + " are nint/nfloat/nstring");
        return;
      }
      if (!Whole(c.substr(0, slash), line, &counts[i])) return;
      if (counts[i] < 0) {
        Fail(line, "tag " + Shown(name) + ": a negative count");
        return;
      }
      // Each count is at most the line's arguments, so their sum below cannot overflow.
      if (counts[i] > static_cast<long long>(w.size()) - 3) {
        Fail(line, "tag " + Shown(name) + ": " + Shown(w[2]) + " asks for more than the " +
                       std::to_string(w.size() - 3) + " arguments found");
        return;
      }
      if (slash != std::string_view::npos) c = c.substr(slash + 1);
    }
    if (static_cast<long long>(w.size()) - 3 != counts[0] + counts[1] + counts[2]) {
      Fail(line, "tag " + Shown(name) + ": " + Shown(w[2]) + " asks for " +
                     std::to_string(counts[0] + counts[1] + counts[2]) + " arguments, found " +
                     std::to_string(w.size() - 3));
      return;
    }
    std::vector<int> ints;
    std::vector<double> floats;
    std::vector<std::string_view> strings;
    std::size_t at = 3;
    for (long long i = 0; i < counts[0]; ++i) {
      long long k = 0;
      if (!Whole(w[at++], line, &k)) return;
      if (k < 0 || k > 1'000'000'000) {
        Fail(line, "tag " + Shown(name) + ": index " + std::to_string(k) + " is out of range");
        return;
      }
      ints.push_back(static_cast<int>(k));
    }
    for (long long i = 0; i < counts[1]; ++i) {
      double x = 0.0;
      if (!Number(w[at++], line, &x)) return;
      floats.push_back(x);
    }
    for (long long i = 0; i < counts[2]; ++i) strings.push_back(w[at++]);

    auto vertexInRange = [&](int v) {
      return v < static_cast<int>(mesh_.points.size()) ||
             Fail(line, "tag " + Shown(name) + ": vertex " + std::to_string(v) + " is out of range (" +
                            std::to_string(mesh_.points.size()) + " vertices read so far, from 0)");
    };
    if (name == "crease") {
      const std::size_t edges = ints.size() > 1 ? ints.size() - 1 : 0;
      if (ints.size() < 2 || (floats.size() != 1 && floats.size() != edges)) {
        Fail(line, "tag \"crease\" takes a chain of 2 or more vertices and one sharpness, or one per edge");
        return;
      }
      for (int v : ints)
        if (!vertexInRange(v)) return;
      for (std::size_t e = 0; e < edges; ++e)
        mesh_.creases.push_back({{ints[e], ints[e + 1]}, floats.size() == 1 ? floats[0] : floats[e]});
    } else if (name == "corner") {
      if (ints.empty() || (floats.size() != 1 && floats.size() != ints.size())) {
        Fail(line, "tag \"corner\" takes vertices and one sharpness, or one per vertex");
        return;
      }
      for (std::size_t i = 0; i < ints.size(); ++i) {
        if (!vertexInRange(ints[i])) return;
        mesh_.corners.emplace_back(ints[i], floats.size() == 1 ? floats[0] : floats[i]);
      }
    } else if (name == "hole") {
      if (ints.empty()) {
        Fail(line, "tag \"hole\" takes the faces to leave out, from 0");
        return;
      }
      for (int f : ints) holes_.emplace_back(f, line);
    } else if (name == "interpolateboundary") {
      int mode = -1;
      if (ints.size() == 1 && floats.empty() && strings.empty()) mode = ints[0];
      if (ints.empty() && floats.empty() && strings.size() == 1) {
        const std::string_view s = strings[0];
        mode = s == "none" ? 0 : s == "edgeandcorner" ? 1 : s == "edgeonly" ? 2 : -1;
      }
      if (mode < 0 || mode > 2) {
        Fail(line, "tag \"interpolateboundary\" takes 0, 1 or 2 (or none, edgeandcorner, edgeonly)");
        return;
      }
      mesh_.interpolateBoundary = mode;
    } else if (name == "facevaryinginterpolateboundary") {
      // OpenSubdiv's numbers, as its shape files use them: 0 smooth, 1 corners kept, 2 and
      // 3 more corners kept, 4 boundaries linear, 5 bilinear everywhere.
      if (ints.size() != 1 || ints[0] > 5 || !floats.empty() || !strings.empty()) {
        Fail(line, "tag \"facevaryinginterpolateboundary\" takes one of 0 to 5");
        return;
      }
      mesh_.faceVaryingRule = static_cast<FaceVaryingRule>(ints[0]);
    } else {
      auto [it, inserted] = skipped_.try_emplace("t " + std::string(name.substr(0, kKindChars)), line, 0);
      ++it->second.second;
    }
  }

  std::string_view text_;
  std::string name_;
  SubdivMesh mesh_;
  std::vector<int> faceLines_;
  std::vector<std::pair<int, int>> holes_;  // face, line
  std::size_t normals_ = 0;
  int firstFaceWithoutTexCoords_ = 0;
  std::map<std::string, std::pair<int, int>> skipped_;  // kind: first line, count
  std::optional<SourceError> error_;
  Scene scene_;
};

}  // namespace

std::variant<Scene, SourceError> ParseObj(std::string_view text, const std::string& name, const ObjOptions& options) {
  return ObjParser(text, name, options).Parse();
}

std::variant<Scene, SourceError> ReadObj(const std::string& path, const ObjOptions& options) {
  auto text = ReadTextFile(path);
  if (auto* e = std::get_if<SourceError>(&text)) return *e;
  return ParseObj(std::get<std::string>(text), path, options);
}

}  // namespace patchscan
