// Subdivision faces through the exact scan, against the independent ray caster, sample by
// sample (xscan/agreement.h): every cage of tests/patch/cages.h from two views, so that
// silhouettes cross regular faces, irregular ones and sub-faces, and no crack between
// faces lets a sample through.
#include <gtest/gtest.h>

#include <cctype>

#include "patch/cages.h"
#include "patch/surface.h"
#include "xscan/agreement.h"

namespace patchscan {
namespace {

// One test per cage, so that ctest runs them side by side (the ray caster is slow under
// the sanitizers).
class EveryCage : public ::testing::TestWithParam<std::size_t> {};

TEST_P(EveryCage, AgreesWithTheRayCaster) {
  const test::Cage c = test::Cages()[GetParam()];
  std::vector<Surface> surfaces;
  for (SubdivFace& f : PrepareSubdivFaces(c.mesh)) surfaces.push_back(Surface{std::move(f), Affine3::Identity()});
  for (const Vec3& eye : {Vec3(3.1, -4.2, 2.6), Vec3(-0.7, 1.3, -5.0)}) test::ExpectAgree(surfaces, test::View(eye, 40), c.name);
}

INSTANTIATE_TEST_SUITE_P(SubdivScan, EveryCage, ::testing::Range<std::size_t>(0, test::Cages().size()),
                         [](const ::testing::TestParamInfo<std::size_t>& info) {
                           const std::vector<test::Cage> cages = test::Cages();
                           std::string name;
                           for (const char ch : cages[info.param].name)
                             name += std::isalnum(static_cast<unsigned char>(ch)) != 0 ? ch : '_';
                           return name;
                         });

}  // namespace
}  // namespace patchscan
