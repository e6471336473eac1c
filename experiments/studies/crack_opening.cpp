#include "experiments/studies/crack_opening.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/crack_embedding.hpp"
#include "meshless/verification/box_mesh.hpp"
#include "meshless/efg/efg_model.hpp"
#include "reference_fem/fem_model.hpp"

namespace experiments {
namespace {

constexpr double kLx = 0.04, kLy = 0.02, kLz = 0.02;  // [m]
constexpr double kCutY = 0.01, kCutDepth = 0.01;
constexpr double kPull = 60.0;  // [Pa] on y = Ly: about 1 % strain
const core::KelvinParameters kMaterial{6000.0, 12000.0, 18000.0, 0.3, 0.0};

core::FaceTag tag(const Eigen::Vector3d& centroid) {
  if (centroid.y() < 1e-9) return core::FaceTag::fixed;
  if (centroid.y() > kLy - 1e-9) return core::FaceTag::load;
  return core::FaceTag::free_surface;
}

}  // namespace

core::RuledSurface crack_opening_cut() {
  return core::RuledSurface({Eigen::Vector3d(0.01, kCutY, kLz), Eigen::Vector3d(0.03, kCutY, kLz)},
                            -Eigen::Vector3d::UnitZ(), kCutDepth);
}

std::vector<Eigen::Vector3d> crack_opening_profile() {
  std::vector<Eigen::Vector3d> p;
  for (int k = 0; k < 10; ++k) p.emplace_back(0.02, kCutY, kLz - 0.0005 - k * 0.001);
  for (int k = 0; k < 10; ++k) p.emplace_back(0.0105 + k * 0.002, kCutY, kLz - 0.005);
  return p;
}

std::vector<double> fem_crack_opening(double size, std::size_t* dofs) {
  const core::RuledSurface cut = crack_opening_cut();
  core::TetMesh mesh = core::mesh_cracked_block(Eigen::Vector3d::Zero(), Eigen::Vector3d(kLx, kLy, kLz), cut, size);
  for (int f = 0; f < mesh.boundary_faces.rows(); ++f) {
    if (mesh.face_tags[f] == core::FaceTag::crack) continue;
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < 3; ++k) c += mesh.vertices.row(mesh.boundary_faces(f, k)).transpose() / 3.0;
    mesh.face_tags[f] = tag(c);
  }
  // Each profile point a hair off the crack on both lips: the shared rule (core::RuledSurface::side) puts it on the
  // lip its side names.
  const std::vector<Eigen::Vector3d> points = crack_opening_profile();
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
  reference_fem::FemRunOptions options;
  options.cut = &cut;
  const reference_fem::FemRunResult r = reference_fem::solve_on_mesh(mesh, p, bc, {0.0}, samples, options);
  std::vector<double> opening;
  for (std::size_t k = 0; k < points.size(); ++k) {
    if (r.sample_offsets[2 * k] + r.sample_offsets[2 * k + 1] > 1e-7)
      throw std::runtime_error("fem_crack_opening: a profile point was not found inside its lip's cells");
    opening.push_back(r.sample_displacements(2 * k, 1) - r.sample_displacements(2 * k + 1, 1));
  }
  if (dofs) *dofs = r.n_dofs;
  return opening;
}

std::vector<double> efg_crack_opening(meshless::CutTreatment treatment, double spacing, double front_transition,
                                      int* nodes) {
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
  p.cut = crack_opening_cut();
  p.cut_treatment = treatment;
  p.front_transition = front_transition;
  meshless::EfgModel model(std::move(p));
  model.run();
  std::vector<double> opening;
  for (const Eigen::Vector3d& x : crack_opening_profile())
    opening.push_back(model.displacement_at(x, +1).y() - model.displacement_at(x, -1).y());
  if (nodes) *nodes = model.statistics().num_nodes;
  return opening;
}

double largest_difference_of_peak(const std::vector<double>& a, const std::vector<double>& reference) {
  double worst = 0.0, peak = 0.0;
  for (std::size_t k = 0; k < reference.size(); ++k) {
    worst = std::max(worst, std::abs(a.at(k) - reference[k]));
    peak = std::max(peak, reference[k]);
  }
  return worst / peak;
}

}  // namespace experiments
