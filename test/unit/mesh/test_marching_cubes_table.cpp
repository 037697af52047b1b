// The 256-case table is computed, not copied: these tests pin down that it is right.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <map>
#include <set>

#include "stereo_fusion/mesh/CellPolygonizer.h"

using namespace stereo_fusion;
using namespace stereo_fusion::mc;

namespace {

int edgeBetween(int a, int b) {
  for (int e = 0; e < 12; ++e) {
    const CubeEdge& ce = cubeEdges()[e];
    if ((ce.corner_a == a && ce.corner_b == b) || (ce.corner_a == b && ce.corner_b == a)) return e;
  }
  return -1;
}

/// Directed edges (between crossing edge ids) of a case's triangles that have no reverse:
/// the surface's trace on the cube's boundary.
std::set<std::pair<int, int>> boundaryOf(int k) {
  std::map<std::pair<int, int>, int> count;
  for (const auto& t : caseTable().triangles[k])
    for (int i = 0; i < 3; ++i) ++count[{t[i], t[(i + 1) % 3]}];
  std::set<std::pair<int, int>> boundary;
  for (const auto& [e, n] : count) {
    EXPECT_EQ(n, 1) << "case " << k << " uses a directed edge twice";
    if (!count.count({e.second, e.first})) boundary.insert(e);
  }
  return boundary;
}

bool onFace(int edge, int axis, int bit) {
  const CubeEdge& e = cubeEdges()[edge];
  return ((e.corner_a >> axis) & 1) == bit && ((e.corner_b >> axis) & 1) == bit;
}

}  // namespace

TEST(MarchingCubesTable, EmptyAndFullCasesHaveNoTriangles) {
  EXPECT_TRUE(caseTable().triangles[0].empty());
  EXPECT_TRUE(caseTable().triangles[255].empty());
}

TEST(MarchingCubesTable, SingleCornerCutOffByOneTriangleFacingAway) {
  for (int c = 0; c < 8; ++c) {
    const auto& tris = caseTable().triangles[1 << c];
    ASSERT_EQ(tris.size(), 1u) << "corner " << c;
    std::set<int> edges(tris[0].begin(), tris[0].end());
    std::set<int> expected;
    for (int axis = 0; axis < 3; ++axis) expected.insert(edgeBetween(c, c ^ (1 << axis)));
    EXPECT_EQ(edges, expected);
    // The normal points away from the inside corner (towards negative SDF): use edge midpoints.
    auto mid = [](int e) {
      const CubeEdge& ce = cubeEdges()[e];
      Eigen::Vector3f p(0, 0, 0);
      for (int corner : {ce.corner_a, ce.corner_b})
        p += Eigen::Vector3f(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1) * 0.5f;
      return p;
    };
    const Eigen::Vector3f a = mid(tris[0][0]), b = mid(tris[0][1]), d = mid(tris[0][2]);
    const Eigen::Vector3f n = (b - a).cross(d - a);
    const Eigen::Vector3f corner(c & 1, (c >> 1) & 1, (c >> 2) & 1);
    EXPECT_GT(n.dot(a - corner), 0.0f) << "corner " << c;
  }
}

TEST(MarchingCubesTable, TrianglesUseOnlySignChangingEdges) {
  for (int k = 0; k < 256; ++k)
    for (const auto& t : caseTable().triangles[k])
      for (int e : t) {
        const CubeEdge& ce = cubeEdges()[e];
        EXPECT_NE((k >> ce.corner_a) & 1, (k >> ce.corner_b) & 1) << "case " << k;
      }
}

TEST(MarchingCubesTable, EveryTraceLiesOnAFaceAndEverySignChangeIsUsed) {
  for (int k = 1; k < 255; ++k) {
    for (const auto& [a, b] : boundaryOf(k)) {
      bool shared_face = false;
      for (int axis = 0; axis < 3; ++axis)
        for (int bit = 0; bit < 2; ++bit)
          shared_face |= onFace(a, axis, bit) && onFace(b, axis, bit);
      EXPECT_TRUE(shared_face) << "case " << k << ": trace segment crosses the cube interior";
    }
    std::set<int> used;
    for (const auto& t : caseTable().triangles[k]) used.insert(t.begin(), t.end());
    for (int e = 0; e < 12; ++e) {
      const CubeEdge& ce = cubeEdges()[e];
      EXPECT_EQ(used.count(e) == 1, ((k >> ce.corner_a) & 1) != ((k >> ce.corner_b) & 1))
          << "case " << k << " edge " << e;
    }
  }
}

TEST(MarchingCubesTable, NeighbouringCubesTraceSharedFacesIdentically) {
  // For every pair of cases that agree on a shared face (all 3 axes, ambiguous faces included),
  // the surface traces on that face are the same segments in opposite directions: no cracks.
  int pairs = 0;
  for (int axis = 0; axis < 3; ++axis) {
    for (int lo = 0; lo < 256; ++lo)
      for (int hi = 0; hi < 256; ++hi) {
        bool agree = true;
        for (int c = 0; c < 8 && agree; ++c)
          if ((c >> axis) & 1) agree = ((lo >> c) & 1) == ((hi >> (c ^ (1 << axis))) & 1);
        if (!agree) continue;
        ++pairs;
        // Map the low cube's +axis face edges onto the high cube's −axis face edges.
        std::set<std::pair<int, int>> from_lo, from_hi;
        for (const auto& [a, b] : boundaryOf(lo))
          if (onFace(a, axis, 1) && onFace(b, axis, 1)) {
            auto shift = [&](int e) {
              const CubeEdge& ce = cubeEdges()[e];
              return edgeBetween(ce.corner_a ^ (1 << axis), ce.corner_b ^ (1 << axis));
            };
            from_lo.insert({shift(b), shift(a)});  // reversed
          }
        for (const auto& seg : boundaryOf(hi))
          if (onFace(seg.first, axis, 0) && onFace(seg.second, axis, 0)) from_hi.insert(seg);
        ASSERT_EQ(from_lo, from_hi) << "axis " << axis << " cases " << lo << " | " << hi;
      }
  }
  EXPECT_EQ(pairs, 3 * 256 * 16);
}

TEST(MarchingCubesTable, GenericPolygonizerMatchesTableOnACube) {
  // A subdivided face must give the same surface trace as the plain face when the extra
  // corners' values are linear along the edges (hanging points on a cube edge).
  const std::vector<std::vector<int>>& faces = cubeFaces();
  for (int k = 1; k < 255; ++k) {
    float values[8];
    for (int c = 0; c < 8; ++c) values[c] = (k >> c) & 1 ? 1.0f : -1.0f;
    std::vector<std::array<Crossing, 3>> tris;
    polygonizeCell(faces, values, &tris);
    EXPECT_EQ(tris.size(), caseTable().triangles[k].size()) << "case " << k;
  }
}
