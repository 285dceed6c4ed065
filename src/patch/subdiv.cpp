#include "patch/subdiv.h"

#include <Eigen/Core>
#include <opensubdiv/bfr/refinerSurfaceFactory.h>
#include <opensubdiv/bfr/surface.h>
#include <opensubdiv/bfr/tessellation.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <mutex>
#include <optional>
#include <stdexcept>

#include "core/check.h"
#include "patch/bicubic.h"
#include "patch/subdiv_pieces.h"
#include "patch/subdiv_topology.h"

namespace patchscan {

namespace osd = OpenSubdiv;

namespace {

// Step of the differences that give an irregular face's second derivatives
// (SubdivFace::Evaluate): truncation ~step times the third derivative, ~1e-6 of the
// second's size on faces of size ~1; rounding ~1e-16 / step far below.
constexpr double kSecondDiffStep = 1e-6;

}  // namespace

// A prepared base face: its Bfr surfaces (points and, where the cage has them, texture
// coordinates) and their patch points.
struct FaceData {
  osd::Bfr::Surface<double> surface;
  std::vector<double> patchPoints;  // x y z per point: the control points, then any Bfr adds
  osd::Bfr::Surface<double> stSurface;
  std::vector<double> stPatchPoints;  // s t per point
  // Per sub-face (one for a quadrilateral), where it is a bicubic polynomial or a Gregory
  // patch (Catmull-Clark and bilinear faces; none for Loop's, whose regular pieces are
  // quartic): fitted when a scan first holds the sub-face (Cage::Hold), under the cage's
  // mutex, and read lock-free. Null until then, so every evaluation of a sub-face is Bfr's
  // before its scan's hold and the pieces' after it, whatever other threads do with the
  // face's other sub-faces.
  mutable std::vector<std::atomic<const BicubicPieces*>> pieces;
  double fitTol = 0.0;  // kBicubicFitRel of the patch points' extent
  FaceData() = default;
  FaceData(const FaceData&) = delete;
  FaceData& operator=(const FaceData&) = delete;
  ~FaceData() {
    for (auto& p : pieces) delete p.load(std::memory_order_relaxed);
  }
};

class SubdivFace::Cage {
 public:
  Cage(const SubdivMesh& mesh, std::unique_ptr<osd::Far::TopologyRefiner> refiner)
      : mesh_(mesh), refiner_(std::move(refiner)), factory_(*refiner_), slots_(static_cast<std::size_t>(mesh.faceSizes.size())) {
    points_.reserve(mesh.points.size() * 3);
    for (const Vec3& p : mesh.points) points_.insert(points_.end(), {p.x(), p.y(), p.z()});
    st_.reserve(mesh.st.size() * 2);
    for (const Vec2& t : mesh.st) st_.insert(st_.end(), {t.x(), t.y()});
  }
  ~Cage() {
    for (Slot& s : slots_) delete s.data.load(std::memory_order_relaxed);
  }
  Cage(const Cage&) = delete;
  Cage& operator=(const Cage&) = delete;

  const SubdivMesh& Mesh() const { return mesh_; }
  const osd::Far::TopologyRefiner& Refiner() const { return *refiner_; }
  const osd::Bfr::RefinerSurfaceFactory<>& Factory() const { return factory_; }

  // The prepared face, prepared now if it is not. Lock-free once prepared.
  const FaceData& Data(int face) {
    Slot& slot = slots_[static_cast<std::size_t>(face)];
    if (const FaceData* d = slot.data.load(std::memory_order_acquire)) return *d;
    const std::lock_guard lock(mutex_);
    if (const FaceData* d = slot.data.load(std::memory_order_relaxed)) return *d;
    auto* d = new FaceData;
    Prepare(face, d);
    slot.data.store(d, std::memory_order_release);
    nPeak_ = std::max(nPeak_, ++nPrepared_);
    ++nPreparations_;
    return *d;
  }
  // Initialises `out` for the face's points and computes its patch points (the face has a
  // limit surface: checked when the cage was made).
  void Prepare(int face, FaceData* out) const {
    const osd::Bfr::Surface<double>::PointDescriptor xyz(3), st(2);
    factory_.InitVertexSurface(face, &out->surface);
    out->patchPoints.resize(static_cast<std::size_t>(out->surface.GetNumPatchPoints()) * 3);
    out->surface.PreparePatchPoints(points_.data(), xyz, out->patchPoints.data(), xyz);
    const osd::Bfr::Parameterization param = out->surface.GetParameterization();
    if (param.GetType() != osd::Bfr::Parameterization::TRI) {
      Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
      for (std::size_t k = 0; k + 2 < out->patchPoints.size(); k += 3) {
        const Eigen::Vector3d q(out->patchPoints[k], out->patchPoints[k + 1], out->patchPoints[k + 2]);
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
      }
      out->fitTol = kBicubicFitRel * (hi - lo).maxCoeff();
      const bool quad = param.GetType() == osd::Bfr::Parameterization::QUAD;
      out->pieces = std::vector<std::atomic<const BicubicPieces*>>(quad ? 1 : static_cast<std::size_t>(param.GetFaceSize()));
    }
    if (mesh_.st.empty()) return;
    switch (mesh_.stClass) {
      case StClass::Vertex: factory_.InitVertexSurface(face, &out->stSurface); break;
      case StClass::Varying: factory_.InitVaryingSurface(face, &out->stSurface); break;
      case StClass::FaceVarying: factory_.InitFaceVaryingSurface(face, &out->stSurface, 0); break;
    }
    out->stPatchPoints.resize(static_cast<std::size_t>(out->stSurface.GetNumPatchPoints()) * 2);
    out->stSurface.PreparePatchPoints(st_.data(), st, out->stPatchPoints.data(), st);
  }
  // A hold that fits (a scan's) also fits sub-face `subFace`'s bicubic pieces if they are
  // not yet: the hold is taken first, so the face stays prepared while they are fitted.
  void Hold(int face, int subFace, bool fit) {
    {
      const std::lock_guard lock(mutex_);
      ++slots_[static_cast<std::size_t>(face)].holds;
    }
    if (!fit) return;
    try {
      const FaceData& data = Data(face);
      const std::size_t k = static_cast<std::size_t>(std::max(subFace, 0));
      if (k >= data.pieces.size()) return;  // a Loop face
      const std::lock_guard lock(mutex_);
      if (data.pieces[k].load(std::memory_order_relaxed)) return;
      const osd::Bfr::Parameterization param = data.surface.GetParameterization();
      auto pieces = std::make_unique<const BicubicPieces>(data.surface, data.patchPoints, MapOf(param, subFace),
                                                          data.fitTol, CornersOf(face, subFace, param));
      data.pieces[k].store(pieces.release(), std::memory_order_release);
    } catch (...) {
      Release(face);  // the holder's constructor fails: no release will come for this hold
      throw;
    }
  }
  // The extraordinary corners of a Catmull-Clark quadrilateral or triangle's sub-face,
  // as BicubicPieces takes them (none known for other faces and schemes).
  BicubicPieces::Corners CornersOf(int face, int subFace, const osd::Bfr::Parameterization& param) const {
    BicubicPieces::Corners c;
    if (mesh_.scheme != SubdivScheme::CatmullClark) return c;
    const osd::Far::TopologyLevel& level = refiner_->GetLevel(0);
    const auto fv = level.GetFaceVertices(face);
    if (param.GetType() == osd::Bfr::Parameterization::QUAD && subFace < 0) {
      // Bfr's corners (0,0), (1,0), (1,1), (0,1) are the face's vertices in order.
      constexpr unsigned kQuadrant[4] = {1u << 0, 1u << 1, 1u << 3, 1u << 2};
      for (int k = 0; k < 4; ++k)
        if (SmoothExtraordinary(level, fv[k])) c.gregoryCells |= kQuadrant[k];
    } else if (param.GetType() == osd::Bfr::Parameterization::TRI && subFace >= 0) {
      // MapOf's kite: (0,0) the triangle's corner `subFace`, (1,1) its centre (valence 3).
      c.gregoryQuadrants = 1u << 3;
      if (SmoothExtraordinary(level, fv[subFace])) c.gregoryCells = 1u << 0;
    }
    return c;
  }
  void Release(int face) {
    const std::lock_guard lock(mutex_);
    Slot& slot = slots_[static_cast<std::size_t>(face)];
    PATCHSCAN_DCHECK(slot.holds > 0, "a sub-face released as many times as held, no more");
    if (slot.holds == 0 || --slot.holds > 0) return;
    if (const FaceData* d = slot.data.exchange(nullptr, std::memory_order_acq_rel)) {
      delete d;
      --nPrepared_;
    }
  }
  long PreparedNow() {
    const std::lock_guard lock(mutex_);
    return nPrepared_;
  }
  long Preparations() {
    const std::lock_guard lock(mutex_);
    return nPreparations_;
  }
  long PeakPrepared() {
    const std::lock_guard lock(mutex_);
    return nPeak_;
  }

 private:
  struct Slot {
    std::atomic<const FaceData*> data{nullptr};
    int holds = 0;  // guarded by mutex_
  };
  const SubdivMesh mesh_;
  std::unique_ptr<osd::Far::TopologyRefiner> refiner_;
  // Bfr's factory and its cache of irregular patch topologies are used under mutex_ only.
  const osd::Bfr::RefinerSurfaceFactory<> factory_;
  std::vector<double> points_, st_;
  std::mutex mutex_;
  std::vector<Slot> slots_;
  long nPrepared_ = 0, nPreparations_ = 0, nPeak_ = 0;
};

SubdivFace::SubdivFace(std::shared_ptr<Cage> cage, int face, int subFace, std::shared_ptr<const std::vector<Vec3>> hull)
    : cage_(std::move(cage)), face_(face), subFace_(subFace), hull_(std::move(hull)) {
  if (subFace_ >= 0) map_ = MapOf(cage_->Factory().GetFaceParameterization(face_), subFace_);
}

const BicubicPieces* SubdivFace::Pieces(const FaceData& face) const {
  const auto k = static_cast<std::size_t>(std::max(subFace_, 0));
  return k < face.pieces.size() ? face.pieces[k].load(std::memory_order_acquire) : nullptr;
}

void SubdivFace::Evaluate(double u, double v, DerivOrder order, SurfaceDerivs* out) const {
  const FaceData& face = cage_->Data(face_);
  if (const BicubicPieces* pc = Pieces(face); pc && pc->Evaluate(u, v, order, out)) return;
  const double* pts = face.patchPoints.data();
  if (Wants(order, DerivOrder::Second) && !face.surface.IsRegular()) {
    // Bfr's irregular patches (Gregory patches at an extraordinary corner) give second
    // derivatives up to 21 % (Catmull-Clark) and 53 % (Loop) off those of their first
    // derivatives, and Newton on the silhouette system, whose Jacobian takes J's gradient
    // from them, can run away (a Loop kite seen edge-on lost its top row). Taken instead as
    // forward differences of the first derivatives kSecondDiffStep apart (backward at the
    // domain's far edges): consistent with them to O(step), two evaluations more.
    EvaluateMapped(face.surface, pts, map_, u, v, DerivOrder::First, out);
    SurfaceDerivs a, b;
    const double hu = u + kSecondDiffStep <= 1.0 ? kSecondDiffStep : -kSecondDiffStep;
    const double hv = v + kSecondDiffStep <= 1.0 ? kSecondDiffStep : -kSecondDiffStep;
    EvaluateMapped(face.surface, pts, map_, u + hu, v, DerivOrder::First, &a);
    EvaluateMapped(face.surface, pts, map_, u, v + hv, DerivOrder::First, &b);
    out->d2pdu2 = (a.dpdu - out->dpdu) / hu;
    out->d2pdv2 = (b.dpdv - out->dpdv) / hv;
    out->d2pduv = 0.5 * ((a.dpdv - out->dpdv) / hu + (b.dpdu - out->dpdu) / hv);
    return;
  }
  EvaluateMapped(face.surface, pts, map_, u, v, order, out);
}

void SubdivFace::EvaluateByBfr(double u, double v, DerivOrder order, SurfaceDerivs* out) const {
  const FaceData& face = cage_->Data(face_);
  EvaluateMapped(face.surface, face.patchPoints.data(), map_, u, v, order, out);
}

bool SubdivFace::BicubicAt(double u, double v) const {
  const BicubicPieces* pc = Pieces(cage_->Data(face_));
  return pc && pc->PatchAt(u, v) >= 0;
}

bool SubdivFace::GregoryAt(double u, double v) const {
  const BicubicPieces* pc = Pieces(cage_->Data(face_));
  return pc && pc->GregoryAt(u, v) >= 0;
}

int SubdivFace::PieceAt(double u, double v) const {
  const BicubicPieces* pc = Pieces(cage_->Data(face_));
  if (!pc) return -1;
  if (const int k = pc->PatchAt(u, v); k >= 0) return k;
  const int g = pc->GregoryAt(u, v);
  return g >= 0 ? BicubicPieces::kCells + g : -1;  // after every bicubic's index
}

int SubdivFace::BicubicCover(std::array<const BicubicPatch*, 16>* out) const {
  const BicubicPieces* pc = Pieces(cage_->Data(face_));
  if (!pc || std::any_of(pc->patchOf.begin(), pc->patchOf.end(), [](std::int8_t k) { return k < 0; })) return -1;
  for (std::size_t k = 0; k < pc->patches.size(); ++k) (*out)[k] = &pc->patches[k];
  return static_cast<int>(pc->patches.size());
}

std::optional<TexCoords> SubdivFace::TextureCoords(double u, double v) const {
  if (cage_->Mesh().st.empty()) return std::nullopt;
  const FaceData& face = cage_->Data(face_);
  const SubFaceMap::Point m = map_.At(u, v);
  const osd::Bfr::Surface<double>::PointDescriptor desc(2);
  double st[2], du[2], dv[2];
  face.stSurface.Evaluate(m.uv, face.stPatchPoints.data(), desc, st, du, dv);
  const Vec2 Du(du[0], du[1]), Dv(dv[0], dv[1]);
  return TexCoords{Vec2(st[0], st[1]), m.AlongU(Du, Dv), m.AlongV(Du, Dv)};
}

bool SubdivFace::Regular() const { return cage_->Data(face_).surface.IsRegular(); }

const SubdivMesh& SubdivFace::Mesh() const { return cage_->Mesh(); }

std::string SubdivFace::Describe() const {
  std::string s = "subdivision face " + std::to_string(face_);
  if (subFace_ >= 0)
    s += " (sub-face " + std::to_string(subFace_) + " of " + std::to_string(cage_->Mesh().faceSizes[static_cast<std::size_t>(face_)]) + ")";
  return s;
}

void SubdivFace::Hold(bool fit) const { cage_->Hold(face_, subFace_, fit); }
void SubdivFace::Release() const { cage_->Release(face_); }
long SubdivFace::PreparedNow() const { return cage_->PreparedNow(); }
long SubdivFace::Preparations() const { return cage_->Preparations(); }
long SubdivFace::PeakPrepared() const { return cage_->PeakPrepared(); }

std::vector<SubdivFace> PrepareSubdivFaces(const SubdivMesh& mesh, SubdivCounts* counts) {
  QuietOpenSubdiv();
  using osd::Far::Index;
  std::unique_ptr<osd::Far::TopologyRefiner> refiner = BuildRefiner(mesh);
  const osd::Far::TopologyLevel& level = refiner->GetLevel(0);
  SubdivCounts c;
  c.faces = level.GetNumFaces();
  c.vertices = level.GetNumVertices();
  c.holes = static_cast<int>(mesh.holes.size());
  for (const SubdivMesh::Crease& k : mesh.creases) c.creaseEdges += static_cast<int>(k.chain.size()) - 1;
  c.corners = static_cast<int>(mesh.corners.size());
  c.textureCoords = !mesh.st.empty();
  for (Index v = 0; v < level.GetNumVertices(); ++v)
    if (!level.IsVertexValenceRegular(v)) ++c.extraordinaryVertices;
  const auto cage = std::make_shared<SubdivFace::Cage>(mesh, std::move(refiner));

  // Step 3: every rendered face's surfaces with a box that contains it. The cage's points
  // give the box of a bilinear face (its corners) and of a regular Catmull-Clark one (its
  // 16 B-spline points); any other face is prepared once here for its patch points (Bfr's
  // bases are non-negative: the surface lies in their hull), then freed.
  const auto& factory = cage->Factory();
  const osd::Far::TopologyLevel& base = cage->Refiner().GetLevel(0);
  std::vector<SubdivFace> faces;
  FaceData scratch;
  for (Index f = 0; f < base.GetNumFaces(); ++f) {
    if (!factory.FaceHasLimitSurface(f)) continue;  // a hole, or a dropped boundary face
    std::vector<Vec3> hullPoints;
    const std::optional<std::vector<int>> ring =
        mesh.scheme == SubdivScheme::CatmullClark ? RegularNeighbourhood(base, f) : std::nullopt;
    if (mesh.scheme == SubdivScheme::Bilinear || ring) {
      for (const int v : ring ? *ring : std::vector<int>(base.GetFaceVertices(f).begin(), base.GetFaceVertices(f).end()))
        hullPoints.push_back(mesh.points[static_cast<std::size_t>(v)]);
    } else {
      cage->Prepare(f, &scratch);
      if (!scratch.surface.IsRegular()) ++c.irregularFaces;
      ++c.boundedAtLoad;
      for (std::size_t k = 0; k + 2 < scratch.patchPoints.size(); k += 3)
        hullPoints.emplace_back(scratch.patchPoints[k], scratch.patchPoints[k + 1], scratch.patchPoints[k + 2]);
    }
    const auto hull = std::make_shared<const std::vector<Vec3>>(std::move(hullPoints));
    const osd::Bfr::Parameterization param = factory.GetFaceParameterization(f);
    if (param.HasSubFaces() || param.GetType() == osd::Bfr::Parameterization::TRI) {
      for (int k = 0; k < param.GetFaceSize(); ++k) faces.emplace_back(cage, f, k, hull);
    } else {
      faces.emplace_back(cage, f, -1, hull);
    }
  }
  c.surfaces = static_cast<int>(faces.size());
  if (counts) *counts = c;
  return faces;
}

CageTessellation TessellateCage(const SubdivMesh& mesh, int rate) {
  QuietOpenSubdiv();
  const std::unique_ptr<osd::Far::TopologyRefiner> refiner = BuildRefiner(mesh);
  const osd::Bfr::RefinerSurfaceFactory<> factory(*refiner);
  std::vector<double> points;
  for (const Vec3& p : mesh.points) points.insert(points.end(), {p.x(), p.y(), p.z()});
  const osd::Bfr::Surface<double>::PointDescriptor xyz(3);
  CageTessellation out;
  osd::Bfr::Surface<double> surface;
  std::vector<double> patchPoints, coords;
  std::vector<int> facets;
  for (int f = 0; f < refiner->GetLevel(0).GetNumFaces(); ++f) {
    if (!factory.InitVertexSurface(f, &surface)) continue;
    patchPoints.resize(static_cast<std::size_t>(surface.GetNumPatchPoints()) * 3);
    surface.PreparePatchPoints(points.data(), xyz, patchPoints.data(), xyz);
    const osd::Bfr::Tessellation tess(surface.GetParameterization(), rate, osd::Bfr::Tessellation::Options().SetFacetSize(3));
    coords.resize(static_cast<std::size_t>(tess.GetNumCoords()) * 2);
    facets.resize(static_cast<std::size_t>(tess.GetNumFacets()) * 3);
    tess.GetCoords(coords.data());
    tess.GetFacets(facets.data());
    const int first = static_cast<int>(out.points.size());
    for (int k = 0; k < tess.GetNumCoords(); ++k) {
      double p[3];
      surface.Evaluate(&coords[2 * static_cast<std::size_t>(k)], patchPoints.data(), xyz, p);
      out.points.emplace_back(p[0], p[1], p[2]);
    }
    for (std::size_t k = 0; k + 2 < facets.size(); k += 3) {
      out.triangles.push_back({first + facets[k], first + facets[k + 1], first + facets[k + 2]});
      // The chord error at the edge midpoints and the centroid, in parameters and in space.
      // A facet across sub-faces of an n-gon has coordinates in two of their tiles (averages
      // of which are no point of the face): not measured, its neighbours are.
      const osd::Bfr::Parameterization param = surface.GetParameterization();
      if (param.HasSubFaces()) {
        int sub[3];
        for (int i = 0; i < 3; ++i) {
          double normalised[2];
          sub[i] = param.ConvertCoordToNormalizedSubFace(&coords[2 * static_cast<std::size_t>(facets[k + static_cast<std::size_t>(i)])], normalised);
        }
        if (sub[0] != sub[1] || sub[1] != sub[2]) continue;
      }
      constexpr double kAt[4][3] = {{0.5, 0.5, 0.0}, {0.0, 0.5, 0.5}, {0.5, 0.0, 0.5}, {1 / 3.0, 1 / 3.0, 1 / 3.0}};
      for (const auto& b : kAt) {
        double uv[2] = {0.0, 0.0}, p[3];
        Vec3 flat = Vec3::Zero();
        for (int i = 0; i < 3; ++i) {
          const int c = facets[k + static_cast<std::size_t>(i)];
          uv[0] += b[i] * coords[2 * static_cast<std::size_t>(c)];
          uv[1] += b[i] * coords[2 * static_cast<std::size_t>(c) + 1];
          flat += b[i] * out.points[static_cast<std::size_t>(first + c)];
        }
        surface.Evaluate(uv, patchPoints.data(), xyz, p);
        out.maxChordError = std::max(out.maxChordError, (Vec3(p[0], p[1], p[2]) - flat).norm());
      }
    }
  }
  return out;
}

}  // namespace patchscan
