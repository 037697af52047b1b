#pragma once
// Which ground-truth triangles a sequence's cameras saw: the truth that scores the accuracy of
// a reconstruction when walls count as solid.

#include <cstdint>
#include <vector>

#include "stereo_fusion/io/FrameSource.h"
#include "stereo_fusion/mesh/SubMesh.h"

namespace stereo_fusion::eval {

/// One entry per triangle of `mesh`: 1 when, in at least one frame, its centroid lies in
/// front of the camera, projects into the image and is the nearest surface of `mesh` there
/// (the mesh's own depth image, rasterizeDepth(), within `tolerance_m` at that pixel). The
/// frames' poses and cameras are used, not their disparities: what the truth hides from the
/// cameras counts as hidden however the matcher erred. Frames that fail to load are skipped.
std::vector<uint8_t> seenTriangles(const TriangleMesh& mesh, const FrameSource& frames,
                                   double tolerance_m, int num_threads = 0);

/// The triangles of `mesh` whose entry in `keep` is set (positions shared, unused ones kept).
TriangleMesh keepTriangles(const TriangleMesh& mesh, const std::vector<uint8_t>& keep);

}  // namespace stereo_fusion::eval
