#pragma once
// A structured tetrahedral mesh of a box, for the verification problems (patch test, cantilever, creep bar)
// and the benchmarks: the vertices are the EFG node cloud, the tets the background integration cells.
#include <Eigen/Core>
#include <functional>

#include "core/tet_mesh.hpp"

namespace meshless {

/// Tag of a boundary face from its centroid and outward unit normal.
using FaceTagger = std::function<core::FaceTag(const Eigen::Vector3d& centroid, const Eigen::Vector3d& normal)>;

/// Box [lo, hi] split into nx by ny by nz hexahedra, each cut into 6 tetrahedra around its main diagonal
/// (Kuhn/Freudenthal split, conforming between neighbours). Boundary quads are split into two outward
/// triangles. Interior vertices are moved by U(-jitter, jitter) * cell size per axis (jitter < 0.25 keeps
/// every tet positive); boundary vertices stay on their faces.
/// @param tagger boundary tags; default: every face free
core::TetMesh make_box_mesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int nx, int ny, int nz,
                            const FaceTagger& tagger = {}, double jitter = 0.0, unsigned seed = 1);

}  // namespace meshless
