#pragma once
// Marching cubes generalised to any box whose boundary is tiled by polygons (thesis §2.5,
// eq. 2.11–2.12, on voxel-centre cubes). The classic 256-case table is this algorithm's
// output on a plain cube, computed once at start-up rather than copied from a listing.
//
// The surface's trace on every boundary polygon is found by the *face rule*: walking the
// polygon, each maximal run of non-negative corners is cut off by one segment from the
// crossing where the run starts to the crossing where it ends. The rule depends only on
// the polygon's own corners, so two cells sharing a polygon trace the same segments (in
// opposite directions) and the union of their triangles has no cracks, ambiguous faces
// included. Segments are linked into closed loops around the cell and fanned into
// triangles whose normals point towards negative SDF (free space, towards the camera).

#include <array>
#include <cstdint>
#include <vector>

namespace stereo_fusion::mc {

/// A surface vertex lies on the boundary edge between polygon corners `a` and `b` (a < b).
struct Crossing {
  int a = 0, b = 0;
  bool operator==(const Crossing& o) const { return a == o.a && b == o.b; }
};

/// Polygonizes one cell. `polygons` lists the boundary polygons as corner indices in
/// counter-clockwise order seen from outside the cell; every polygon edge must be shared
/// with exactly one other polygon of the same cell. `values[i]` is the SDF at corner i;
/// a corner is "inside" (the solid, behind the surface) when values[i] >= 0.
/// Appends triangles (three crossings each) to `triangles`.
void polygonizeCell(const std::vector<std::vector<int>>& polygons, const float* values,
                    std::vector<std::array<Crossing, 3>>* triangles);

/// Unit-cube corners: corner c sits at (c & 1, (c >> 1) & 1, (c >> 2) & 1).
/// Cube edges 0..11: the four x edges, the four y edges, then the four z edges.
struct CubeEdge {
  int corner_a, corner_b;  // corner_a < corner_b; they differ in exactly one bit
};
const std::array<CubeEdge, 12>& cubeEdges();
/// The six cube faces as counter-clockwise corner cycles seen from outside.
const std::vector<std::vector<int>>& cubeFaces();

/// The marching cubes table: for case index k (bit c set ⇔ corner c has SDF ≥ 0), the
/// triangles as triples of cube edge indices. 256 cases, computed from polygonizeCell().
struct CaseTable {
  std::array<std::vector<std::array<uint8_t, 3>>, 256> triangles;
};
const CaseTable& caseTable();

}  // namespace stereo_fusion::mc
