// A block with a crack under an opening (mode I) load: the meshless model's crack (enrichment and visibility, paper
// §4) against the FEM reference's duplicated-node crack (core/crack_embedding.hpp). The cut is the same object for
// both (core::RuledSurface); the opening u_y(+) - u_y(-) along the crack must match within 5 % of its peak.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "core/crack_embedding.hpp"
#include "meshless/box_mesh.hpp"
#include "meshless/efg_model.hpp"
#include "reference_fem/fem_model.hpp"

namespace {

constexpr double kLx = 0.04, kLy = 0.02, kLz = 0.02;  // [m]
constexpr double kCutY = 0.01, kCutDepth = 0.01;
constexpr double kPull = 60.0;  // [Pa] on y = Ly: about 1 % strain
const core::KelvinParameters kMaterial{6000.0, 12000.0, 18000.0, 0.3, 0.0};

// The plane y = 10 mm from the top face z = 20 mm down to z = 10 mm, for 10 <= x <= 30 mm: its normal is +y.
core::RuledSurface block_cut() {
  return core::RuledSurface({Eigen::Vector3d(0.01, kCutY, kLz), Eigen::Vector3d(0.03, kCutY, kLz)},
                            -Eigen::Vector3d::UnitZ(), kCutDepth);
}

core::FaceTag tag(const Eigen::Vector3d& centroid) {
  if (centroid.y() < 1e-9) return core::FaceTag::fixed;
  if (centroid.y() > kLy - 1e-9) return core::FaceTag::load;
  return core::FaceTag::free_surface;
}

/// Points on the crack: its vertical centre line (x = 20 mm, mouth to front) and a line at half depth.
std::vector<Eigen::Vector3d> profile() {
  std::vector<Eigen::Vector3d> p;
  for (int k = 0; k < 10; ++k) p.emplace_back(0.02, kCutY, kLz - 0.0005 - k * 0.001);  // z 19.5 ... 10.5 mm
  for (int k = 0; k < 10; ++k) p.emplace_back(0.0105 + k * 0.002, kCutY, kLz - 0.005);  // x 10.5 ... 28.5 mm
  return p;
}

/// FEM opening along the profile: P2 on the cracked block meshed at `size`.
std::vector<double> fem_opening(double size) {
  core::TetMesh mesh = core::mesh_cracked_block(Eigen::Vector3d::Zero(), Eigen::Vector3d(kLx, kLy, kLz), block_cut(), size);
  for (int f = 0; f < mesh.boundary_faces.rows(); ++f) {
    if (mesh.face_tags[f] == core::FaceTag::crack) continue;
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) c += mesh.vertices.row(mesh.boundary_faces(f, k)).transpose() / 3.0;
    mesh.face_tags[f] = tag(c);
  }
  const std::vector<Eigen::Vector3d> points = profile();
  // Each profile point just off the crack on both lips: the shared rule puts it on the lip its side names.
  Eigen::MatrixXd samples(2 * points.size(), 3);
  for (std::size_t k = 0; k < points.size(); ++k) {
    samples.row(2 * k) = (points[k] + Eigen::Vector3d(0, 1e-8, 0)).transpose();
    samples.row(2 * k + 1) = (points[k] - Eigen::Vector3d(0, 1e-8, 0)).transpose();
  }
  reference_fem::SolverParameters p;
  p.material = kMaterial;
  p.degree = 2;
  reference_fem::BoundaryConditions bc;
  bc.dirichlet.push_back(reference_fem::DirichletCondition{});
  reference_fem::TractionCondition pull;
  pull.traction = Eigen::Vector3d(0.0, kPull, 0.0);
  bc.tractions.push_back(pull);
  const core::RuledSurface cut = block_cut();
  reference_fem::FemRunOptions options;
  options.cut = &cut;
  const reference_fem::FemRunResult r = reference_fem::solve_on_mesh(mesh, p, bc, {0.0}, samples, options);
  std::vector<double> opening;
  for (std::size_t k = 0; k < points.size(); ++k) {
    EXPECT_LT(r.sample_offsets[2 * k] + r.sample_offsets[2 * k + 1], 1e-7) << "profile point " << k;
    opening.push_back(r.sample_displacements(2 * k, 1) - r.sample_displacements(2 * k + 1, 1));
  }
  std::cout << "FEM at " << size * 1e3 << " mm: " << r.n_dofs << " DOFs, " << r.crack_faces << " crack faces\n";
  return opening;
}

/// EFG opening along the profile on a jittered box cloud of about `spacing`.
std::vector<double> efg_opening(meshless::CutTreatment treatment, double spacing, double transition) {
  meshless::EfgProblem p;
  p.name = "cracked block";
  const int nx = static_cast<int>(std::lround(kLx / spacing));
  const int ny = static_cast<int>(std::lround(kLy / spacing)) | 1;  // odd: no node plane on the crack
  const int nz = static_cast<int>(std::lround(kLz / spacing));
  p.mesh = meshless::make_box_mesh(Eigen::Vector3d::Zero(), Eigen::Vector3d(kLx, kLy, kLz), nx, ny, nz,
                                   [](const Eigen::Vector3d& c, const Eigen::Vector3d&) { return tag(c); }, 0.2, 7);
  p.material = kMaterial;
  p.support.d_max = 2.0;
  p.support.k = 6;
  p.quadrature_order = 2;
  p.node_spacing = spacing;
  p.traction = [](const Eigen::Vector3d&) { return Eigen::Vector3d(0.0, kPull, 0.0); };
  p.step_times = {0.0};
  p.cut = block_cut();
  p.cut_treatment = treatment;
  p.front_transition = transition;
  meshless::EfgModel model(std::move(p));
  model.run();
  std::vector<double> opening;
  for (const Eigen::Vector3d& x : profile())
    opening.push_back(model.displacement_at(x, +1).y() - model.displacement_at(x, -1).y());
  std::cout << "EFG " << to_string(treatment) << " at " << spacing * 1e3 << " mm: " << model.statistics().num_nodes
            << " nodes, " << model.statistics().num_lip_points << " lip points\n";
  return opening;
}

TEST(CutOpening, MeshlessCrackOpensLikeTheFemCrack) {
  const std::vector<double> fem = fem_opening(0.0015);
  double peak = 0.0;
  for (double o : fem) peak = std::max(peak, o);
  ASSERT_GT(peak, 0.0);
  for (meshless::CutTreatment treatment : {meshless::CutTreatment::enrichment, meshless::CutTreatment::visibility}) {
    const std::vector<double> efg = efg_opening(treatment, 0.002, 0.002);
    double worst = 0.0;
    std::cout << "opening [um] along the crack, FEM vs EFG " << to_string(treatment) << ":\n";
    for (std::size_t k = 0; k < fem.size(); ++k) {
      std::cout << "  (" << profile()[k].transpose() * 1e3 << ") mm: " << fem[k] * 1e6 << " vs " << efg[k] * 1e6
                << "\n";
      worst = std::max(worst, std::abs(efg[k] - fem[k]));
      EXPECT_GT(efg[k], 0.0) << "the lips separate";
    }
    std::cout << to_string(treatment) << ": largest difference " << 100 * worst / peak << " % of the peak opening "
              << peak * 1e6 << " um\n";
    EXPECT_LT(worst, 0.05 * peak) << to_string(treatment);
  }
}

}  // namespace
