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

// A regular octahedron (every vertex of valence 4) or icosahedron (valence 5) of
// triangles, counter-clockwise seen from outside: for Loop, every vertex extraordinary.
inline SubdivMesh Octahedron() {
  SubdivMesh m;
  m.scheme = SubdivScheme::Loop;
  m.points = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  m.faceSizes.assign(8, 3);
  m.faceVertices = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};
  return m;
}
inline SubdivMesh Icosahedron() {
  SubdivMesh m;
  m.scheme = SubdivScheme::Loop;
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  m.points = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
              {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (Vec3& p : m.points) p /= std::sqrt(1.0 + t * t);
  m.faceSizes.assign(20, 3);
  m.faceVertices = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2, 10, 7, 6, 7, 1, 8,
                    3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5, 2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
  return m;
}

// A torus of nu x nv quadrilaterals, one of them cut into two triangles along a diagonal:
// the diagonal's two ends are extraordinary (valence 5), the faces around them irregular.
inline SubdivMesh Torus(int nu, int nv) {
  SubdivMesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double a = 2.0 * M_PI * i / nu, b = 2.0 * M_PI * j / nv;
      m.points.emplace_back((1.0 + 0.45 * std::cos(b)) * std::cos(a), (1.0 + 0.45 * std::cos(b)) * std::sin(a), 0.45 * std::sin(b));
    }
  auto at = [&](int i, int j) { return ((i + nu) % nu) * nv + (j + nv) % nv; };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const int q[4] = {at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)};
      if (i == 0 && j == 0) {
        m.faceSizes.insert(m.faceSizes.end(), {3, 3});
        m.faceVertices.insert(m.faceVertices.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
      } else {
        m.faceSizes.push_back(4);
        m.faceVertices.insert(m.faceVertices.end(), q, q + 4);
      }
    }
  return m;
}

// Grid(n) with each quadrilateral cut into two triangles along the same diagonal: interior
// vertices of valence 6, Loop's regular case.
inline SubdivMesh TriangleGrid(int n, int interpolateBoundary);

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
  c.push_back({"torus, two vertices of valence 5", Torus(8, 6)});
  c.push_back({"open grid, boundary edges and corners sharp", Grid(4, 1)});
  c.push_back({"open grid, boundary faces dropped", Grid(4, 0)});
  c.push_back({"octahedron, Loop, valence 4", Octahedron()});
  SubdivMesh loopTetra = tetra;
  loopTetra.scheme = SubdivScheme::Loop;
  for (Vec3& p : loopTetra.points) p *= 2.0;  // Loop shrinks a tetrahedron to a third
  c.push_back({"tetrahedron, Loop", loopTetra});
  SubdivMesh creasedIco = Icosahedron();
  creasedIco.creases = {{{0, 11, 5, 0}, 10.0}};
  c.push_back({"icosahedron, Loop, valence 5, a sharp crease", creasedIco});
  c.push_back({"open triangle grid, Loop, boundary sharp", TriangleGrid(3, 1)});
  SubdivMesh flatCube = Cube();
  flatCube.scheme = SubdivScheme::Bilinear;
  c.push_back({"cube, bilinear (the cage flat)", flatCube});
  SubdivMesh flatPyramid = Pyramid(5);
  flatPyramid.scheme = SubdivScheme::Bilinear;
  c.push_back({"pyramid, pentagonal base, bilinear", flatPyramid});
  return c;
}

inline SubdivMesh TriangleGrid(int n, int interpolateBoundary) {
  SubdivMesh m = Grid(n, interpolateBoundary);
  m.scheme = SubdivScheme::Loop;
  std::vector<int> tris;
  for (std::size_t f = 0; f < m.faceSizes.size(); ++f) {
    const int* q = &m.faceVertices[4 * f];
    tris.insert(tris.end(), {q[0], q[1], q[2], q[0], q[2], q[3]});
  }
  m.faceVertices = tris;
  m.faceSizes.assign(tris.size() / 3, 3);
  return m;
}

}  // namespace patchscan::test
