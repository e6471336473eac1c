// An independent FE code on the lung (label long, one and two minutes on 2 cores): lung_small and the cut lung_large,
// exported by `tissue export` at k = 0, solved by CalculiX (ccx) at their linear long-time limit, against our FEM
// reference solved on the same mesh at the same limit. docs/FEM_REFERENCE.md, "An independent FE code: CalculiX".
//
// The reference reaches the limit by one time step of 1e9 relaxation times under the full load: the Kelvin step's
// modulus is then g_inf + (1 - g_inf) tau / dt of K1 (docs/MATERIAL.md §1.3), E_inf to 1e-9 relative. ccx is called
// as a child process; when it is not installed the test FAILS (scripts/install_dependencies.sh installs
// calculix-ccx), since a skipped comparison would read as an agreement.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>

#include <fmt/format.h>

#include "core/case.hpp"
#include "core/geometry.hpp"
#include "core/output_directory.hpp"
#include "experiments/export/case_export.hpp"
#include "reference_fem/fem_model.hpp"

namespace experiments {
namespace {

/// [-] RMS over the samples of |u_ccx - u_ref|, over the largest |u_ref|: measured 4.6e-6 on lung_small's shipped 12 mm
/// mesh and 4.8e-6 on the cut lung_large's (3.1e-5 on lung_small at 18 mm: larger faces, so perhaps the support's
/// taper, which the reference integrates with its face rule and the deck with a 36-point rule; not checked). ccx
/// prints 7 digits (1e-6 relative).
constexpr double kAgreement = 1e-5;

/// The RMS of |u_ccx - u_ref| over the samples of configs/CONFIG at k = 0, relative to the largest |u_ref|.
double calculix_against_reference(const std::string& config) {
  EXPECT_EQ(std::system("command -v ccx > /dev/null 2>&1"), 0)
      << "CalculiX (ccx) is not on PATH: install the Debian package calculix-ccx (scripts/install_dependencies.sh)";
  core::Case c = core::load_case(std::string(TISSUE_TEST_CONFIG_DIR) + "/" + config);
  c.material.k = 0.0;  // the linear limit both codes solve
  core::GeometryOptions options;  // the shipped 12 mm mesh
  options.build_node_cloud = false;
  const core::Geometry g = core::build_geometry(c, options);

  const std::filesystem::path folder = std::filesystem::temp_directory_path() / ("tissue_test_calculix_" + c.name);
  std::filesystem::remove_all(folder);
  core::OutputDirectory out(folder);
  write_case_export(c, g, out.staging());
  out.commit();
  const auto ccx_start = std::chrono::steady_clock::now();
  const std::string command = fmt::format("cd '{}' && ccx -i job > ccx.log 2>&1", folder.string());
  EXPECT_EQ(std::system(command.c_str()), 0) << "ccx failed; see " << (folder / "ccx.log").string();
  const double ccx_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - ccx_start).count();
  const ModelResult calculix = calculix_samples(folder, folder / "job.dat");

  // Our reference at the same limit: one step of 1e9 relaxation times under the full load.
  core::Case limit = c;
  limit.time.total = 1e9 * c.material.relaxation_time();
  limit.time.steps = 1;
  limit.time.min_step = 0.0;
  limit.output.vtu = false;
  const reference_fem::FemRunResult reference = reference_fem::run_case(limit, g);

  const Eigen::MatrixXd& u_ref = reference.sample_displacements;
  EXPECT_EQ(calculix.sample_displacements.rows(), u_ref.rows());
  if (calculix.sample_displacements.rows() != u_ref.rows()) return 1.0;
  double peak = 0.0, squared = 0.0;
  for (Eigen::Index i = 0; i < u_ref.rows(); ++i) {
    peak = std::max(peak, u_ref.row(i).norm());
    squared += (calculix.sample_displacements.row(i) - u_ref.row(i)).squaredNorm();
  }
  const double rms = std::sqrt(squared / static_cast<double>(u_ref.rows()));
  std::cout << fmt::format("{}{}, k = 0, long-time limit, 12 mm: {} DOFs; peak |u| {:.6f} mm; RMS |u_ccx - u_ref| "
                           "{:.3e} mm = {:.3e} of the peak; ccx {:.1f} s, reference {:.1f} s\n",
                           c.name, c.cut ? " (cut)" : "", reference.n_dofs, peak * 1e3, rms * 1e3, rms / peak,
                           ccx_seconds, reference.total_seconds);
  EXPECT_GT(peak, 1e-3);  // millimetres: the load reached the samples in both
  std::filesystem::remove_all(folder);
  return rms / peak;
}

TEST(CalculixLung, LongTimeLimitOfLungSmallAgreesWithTheReferenceOnTheSameMesh) {
  EXPECT_LT(calculix_against_reference("lung_small.json"), kAgreement);  // 4.6e-6
}

// The cut case: the crack's two lips are separate faces of the exported mesh (its nodes doubled there), free in both
// codes; samples 2.9 and 3.6 mm from the cut, one on each lip, agree as well as the far ones (4.8e-5 mm each).
TEST(CalculixLung, LongTimeLimitOfTheCutLungLargeAgreesWithTheReferenceOnTheSameMesh) {
  EXPECT_LT(calculix_against_reference("lung_large.json"), kAgreement);  // 4.8e-6
}

}  // namespace
}  // namespace experiments
