#pragma once
// The block of the FEM crack tests (test_fem_crack, test_fem_front_grading): 40 x 20 x 20 mm, cut in the plane
// y = 10 mm from the top face z = 20 mm down 10 mm, for 10 <= x <= 30 mm, so the cut's front is its bottom edge and
// its two vertical edges inside the block. The y = 0 face is tagged fixed and the y = 20 mm face load: a pull in y
// opens the cut (mode I). Linear law (k = 0), P2.
#include <Eigen/Core>
#include <algorithm>

#include "core/crack_embedding.hpp"
#include "reference_fem/fem_model.hpp"

namespace reference_fem::cracked_block {

constexpr double kLx = 0.04, kLy = 0.02, kLz = 0.02;  // [m]
constexpr double kCutY = 0.01, kCutDepth = 0.01;      // [m]

inline core::RuledSurface cut() {
  return core::RuledSurface({Eigen::Vector3d(0.01, kCutY, kLz), Eigen::Vector3d(0.03, kCutY, kLz)},
                            -Eigen::Vector3d::UnitZ(), kCutDepth);
}

/// The block meshed at `size` [m], its front refined to `front_size` when 0 < front_size < size
/// (core::mesh_cracked_block), with y = 0 fixed and y = Ly loaded.
inline core::TetMesh mesh(double size, double front_size = 0.0) {
  core::TetMesh m = core::mesh_cracked_block(Eigen::Vector3d::Zero(), Eigen::Vector3d(kLx, kLy, kLz), cut(), size,
                                             front_size);
  for (int f = 0; f < m.boundary_faces.rows(); ++f) {
    double y_max = -1, y_min = 1;
    for (int k = 0; k < 3; ++k) {
      const double y = m.vertices(m.boundary_faces(f, k), 1);
      y_max = std::max(y_max, y);
      y_min = std::min(y_min, y);
    }
    if (y_max < 1e-9) m.face_tags[f] = core::FaceTag::fixed;
    if (y_min > kLy - 1e-9) m.face_tags[f] = core::FaceTag::load;
  }
  return m;
}

/// The shipped tissue's moduli in the law's linear limit, nu = 0.3, degree 2.
inline SolverParameters linear_parameters() {
  SolverParameters p;
  p.material.K1 = 6000.0;
  p.material.K2 = 12000.0;
  p.material.eta = 18000.0;
  p.material.nu = 0.3;
  p.material.k = 0.0;
  p.degree = 2;
  return p;
}

}  // namespace reference_fem::cracked_block
