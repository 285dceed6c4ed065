// Control cages for the subdivision tests: each exercises a part of Bfr's evaluation (regular
// faces, extraordinary vertices, non-quadrilateral faces, creases, corners, holes and open
// boundaries).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "patch/subdiv.h"

namespace patchscan::test {

struct Cage {
  std::string name;
  SubdivMesh mesh;
};

// The cube [-1,1]^3, faces counter-clockwise seen from outside; every vertex of valence 3.
inline SubdivMesh Cube() {
  SubdivMesh m;
  m.faceSizes = {4, 4, 4, 4, 4, 4};
  m.faceVertices = {0, 1, 3, 2, 2, 3, 5, 4, 4, 5, 7, 6, 6, 7, 1, 0, 1, 7, 5, 3, 6, 0, 2, 4};
  m.points = {{-1, -1, 1}, {1, -1, 1}, {-1, 1, 1}, {1, 1, 1}, {-1, 1, -1}, {1, 1, -1}, {-1, -1, -1}, {1, -1, -1}};
  m.interpolateBoundary = 1;
  return m;
}

// A pyramid over a regular n-gon: its apex has valence n, its base is one n-sided face.
inline SubdivMesh Pyramid(int n) {
  SubdivMesh m;
  for (int k = 0; k < n; ++k) {
    const double a = 2.0 * M_PI * k / n;
    m.points.emplace_back(std::cos(a), std::sin(a), -0.6);
  }
  m.points.emplace_back(0.0, 0.0, 1.0);
  for (int k = 0; k < n; ++k) {
    m.faceSizes.push_back(3);
    m.faceVertices.insert(m.faceVertices.end(), {k, (k + 1) % n, n});
  }
  m.faceSizes.push_back(n);
  for (int k = n - 1; k >= 0; --k) m.faceVertices.push_back(k);  // seen from below
  return m;
}

// An open, wavy grid of n x n quadrilaterals over [-1.5,1.5]^2 in z = bumps.
inline SubdivMesh Grid(int n, int interpolateBoundary) {
  SubdivMesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double x = 3.0 * i / n - 1.5, y = 3.0 * j / n - 1.5;
      m.points.emplace_back(x, y, 0.4 * std::sin(2.1 * x + 0.3) * std::cos(1.7 * y));
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i;
      m.faceSizes.push_back(4);
      m.faceVertices.insert(m.faceVertices.end(), {a, a + 1, a + n + 2, a + n + 1});
    }
  m.interpolateBoundary = interpolateBoundary;
  return m;
}

inline std::vector<Cage> Cages() {
  std::vector<Cage> c;
  c.push_back({"cube", Cube()});
  SubdivMesh creased = Cube();
  creased.creases = {{{0, 1, 3, 2, 0}, 10.0}, {{4, 5, 7, 6, 4}, 1.5}};  // infinitely sharp, semi-sharp
  creased.corners = {{6, 10.0}};
  c.push_back({"cube with creases and a corner", creased});
  SubdivMesh holed = Cube();
  holed.holes = {1};
  c.push_back({"cube with a hole", holed});
  SubdivMesh tetra;
  tetra.faceSizes = {3, 3, 3, 3};
  tetra.faceVertices = {0, 2, 1, 0, 1, 3, 1, 2, 3, 2, 0, 3};
  tetra.points = {{1, 1, 1}, {1, -1, -1}, {-1, 1, -1}, {-1, -1, 1}};
  c.push_back({"tetrahedron", tetra});
  c.push_back({"pyramid, apex of valence 8, octagonal base", Pyramid(8)});
  c.push_back({"pyramid, pentagonal base", Pyramid(5)});
  c.push_back({"open grid, boundary edges and corners sharp", Grid(4, 1)});
  c.push_back({"open grid, boundary faces dropped", Grid(4, 0)});
  return c;
}

}  // namespace patchscan::test
