#pragma once

namespace stereo_fusion {

/// Whether this CPU (and OS) can run the AVX2 paths of the lookup, the fuser and the mesh-level
/// refresh. Those paths give bit-identical results to the scalar ones; they are picked at run
/// time so that one build (-march=x86-64-v2) runs everywhere. Always false off x86.
bool avx2Supported();

}  // namespace stereo_fusion
