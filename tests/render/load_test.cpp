// Parsing of the camera options' values (render/load.h).
#include <gtest/gtest.h>

#include "render/load.h"

namespace patchscan::render {
namespace {

TEST(CameraOptions, ParseVec3) {
  EXPECT_EQ(*ParseVec3("1,-2.5,3e2"), Vec3(1, -2.5, 300));
  for (const char* bad : {"", "1,2", "1,2,3,4", "1,,3", "a,b,c", "1,2,nan", "1,2,inf", "1 2 3"})
    EXPECT_FALSE(ParseVec3(bad)) << bad;
}

TEST(CameraOptions, ParseSize) {
  EXPECT_EQ(*ParseSize("640x480"), std::make_pair(640, 480));
  for (const char* bad : {"", "640", "640x", "x480", "0x10", "-5x5", "10x10x10", "1.5x2"})
    EXPECT_FALSE(ParseSize(bad)) << bad;
}

}  // namespace
}  // namespace patchscan::render
