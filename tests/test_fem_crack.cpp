// The FEM crack pipeline (core/crack_embedding.hpp + reference_fem): a block with a surface-breaking cut
// under an opening (mode I) load. The cut's nodes are duplicated (Gmsh Crack plugin), so its two faces
// separate; away from the cut the displacement stays continuous.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <map>

#include "tests/cracked_block.hpp"

namespace reference_fem {
namespace {

using namespace cracked_block;

struct CrackedBlock {
  core::TetMesh mesh;
  FemRunResult result;
};

CrackedBlock solve_cracked_block(const Eigen::MatrixXd& samples) {
  CrackedBlock b;
  b.mesh = cracked_block::mesh(0.004);
  // y = 0 clamped, y = Ly pulled: the cut is normal to the load, so it opens (mode I).
  BoundaryConditions bc;
  bc.dirichlet.push_back(DirichletCondition{});
  TractionCondition pull;
  pull.traction = Eigen::Vector3d(0.0, 60.0, 0.0);  // [Pa]: about 1 % strain
  bc.tractions.push_back(pull);
  b.result = solve_on_mesh(b.mesh, linear_parameters(), bc, {0.0}, samples, FemRunOptions{});
  return b;
}

TEST(FemCrack, FacesSeparateUnderOpeningLoadAndFieldIsContinuousElsewhere) {
  // Sample pairs straddling y = 0.01 (+-0.3 mm): across the cut near its mouth, and below its front.
  const double d = 3e-4;
  Eigen::MatrixXd samples(4, 3);
  samples << 0.02, kCutY - d, kLz - 0.002,  // across the cut, 2 mm below the top face
      0.02, kCutY + d, kLz - 0.002,         //
      0.02, kCutY - d, 0.004,               // 6 mm below the crack front: uncut material
      0.02, kCutY + d, 0.004;
  const CrackedBlock b = solve_cracked_block(samples);
  const core::TetMesh& m = b.mesh;
  int n_crack_faces = 0;
  for (auto t : m.face_tags) n_crack_faces += t == core::FaceTag::crack;
  EXPECT_GT(n_crack_faces, 20);

  // Duplicated node pairs: same position, different index. All of them must lie on the cut.
  std::map<std::array<long long, 3>, std::vector<int>> by_position;
  for (int v = 0; v < m.num_vertices(); ++v) {
    std::array<long long, 3> key{};
    for (int k = 0; k < 3; ++k) key[k] = std::llround(m.vertices(v, k) * 1e9);
    by_position[key].push_back(v);
  }
  // Which side of the cut a vertex belongs to: the mean y of the tets using it.
  std::vector<double> side_y(m.num_vertices(), 0.0);
  std::vector<int> uses(m.num_vertices(), 0);
  for (int t = 0; t < m.num_tets(); ++t) {
    double y = 0;
    for (int k = 0; k < 4; ++k) y += m.vertices(m.tets(t, k), 1) / 4;
    for (int k = 0; k < 4; ++k) {
      side_y[m.tets(t, k)] += y;
      ++uses[m.tets(t, k)];
    }
  }
  const Eigen::MatrixXd& u = b.result.vertex_displacements;
  const double u_max = u.rowwise().norm().maxCoeff();
  int pairs = 0;
  double max_opening = 0.0, min_normal_opening = 1e9;
  for (const auto& [key, vs] : by_position) {
    if (vs.size() < 2) continue;
    ASSERT_EQ(vs.size(), 2u);
    ++pairs;
    const Eigen::Vector3d x = m.vertices.row(vs[0]).transpose();
    EXPECT_NEAR(x.y(), kCutY, 1e-9);
    EXPECT_GE(x.z(), kLz - kCutDepth - 1e-9);
    int plus = vs[0], minus = vs[1];
    if (side_y[plus] / uses[plus] < side_y[minus] / uses[minus]) std::swap(plus, minus);
    const Eigen::Vector3d jump = (u.row(plus) - u.row(minus)).transpose();
    max_opening = std::max(max_opening, jump.norm());
    min_normal_opening = std::min(min_normal_opening, jump.y());
  }
  std::cout << "crack faces " << n_crack_faces << ", duplicated pairs " << pairs << ", max |u| " << u_max * 1e3
            << " mm, max opening " << max_opening * 1e3 << " mm, min normal opening " << min_normal_opening * 1e3
            << " mm\n";
  EXPECT_GT(pairs, 10);
  EXPECT_GT(max_opening, 0.2 * u_max);            // a measurable opening
  EXPECT_GT(min_normal_opening, -1e-6 * u_max);  // the faces separate, they never interpenetrate

  const Eigen::MatrixXd& s = b.result.sample_displacements;
  for (int i = 0; i < 4; ++i) {
    EXPECT_LT(b.result.sample_offsets[i], 1e-12);  // inside the mesh, located on its own side of the cut
    std::cout << "sample " << i << " u = " << s.row(i) * 1e3 << " mm\n";
  }
  const double across = (s.row(1) - s.row(0)).norm();
  const double below = (s.row(3) - s.row(2)).norm();
  std::cout << "jump across the cut " << across * 1e3 << " mm, below the front " << below * 1e3 << " mm\n";
  EXPECT_GT(across, 0.1 * u_max);
  EXPECT_LT(below, 0.1 * across);  // continuous there: only the smooth gradient over 0.6 mm
}

}  // namespace
}  // namespace reference_fem
