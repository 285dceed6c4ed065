// Subdivision faces through the exact scan, against the independent ray caster, sample by
// sample (xscan/agreement.h): every cage of tests/patch/cages.h from two views, so that
// silhouettes cross regular faces, irregular ones and sub-faces, and no crack between
// faces lets a sample through.
#include <gtest/gtest.h>

#include "patch/cages.h"
#include "patch/surface.h"
#include "xscan/agreement.h"

namespace patchscan {
namespace {

TEST(SubdivScan, EveryCageAgreesWithTheRayCaster) {
  for (const test::Cage& c : test::Cages()) {
    std::vector<Surface> surfaces;
    for (SubdivFace& f : PrepareSubdivFaces(c.mesh)) surfaces.push_back(Surface{std::move(f), Affine3::Identity()});
    for (const Vec3& eye : {Vec3(3.1, -4.2, 2.6), Vec3(-0.7, 1.3, -5.0)})
      test::ExpectAgree(surfaces, test::View(eye, 40), c.name);
  }
}

}  // namespace
}  // namespace patchscan
