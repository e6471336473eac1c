// `tissue verify fem` under mpirun (label `mpi`): the lung levels of a mesh study solved by two processes together,
// against the same study on one process. A study's finest level may need more memory than one process has
// (docs/FEM_REFERENCE.md, "Running distributed"); under mpirun rank 0 meshes each level and both processes solve it.
// This suite runs on one process and starts both studies as child processes (TISSUE_MPIEXEC, set by
// tests/CMakeLists.txt, with the OpenMPI settings that let it run as root and on fewer cores than processes).
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/tissue_process.hpp"

namespace {

namespace fs = std::filesystem;
using tissue_test::run_command;
using tissue_test::run_tissue;

/// What both studies run: the CI-sized lung at two coarse levels and the closed forms at one cantilever level.
std::string study_arguments(const fs::path& out) {
  return "verify fem --config " + std::string(TISSUE_TEST_CONFIG_DIR) +
         "/ci/lung_small_ci.json --sizes 27 18 --cantilever-levels 1 --out " + out.string();
}

nlohmann::json read_levels(const fs::path& folder) {
  std::ifstream in(folder / "fem.json");
  EXPECT_TRUE(in.good()) << "no " << (folder / "fem.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  return j.at("mesh_convergence").at("lung_small_ci").at("levels");
}

/// The largest difference between two levels' sample displacements, relative to the largest sample.
double relative_difference(const nlohmann::json& a, const nlohmann::json& b) {
  double largest = 0.0, difference = 0.0;
  const auto& ua = a.at("sample_displacements_mm");
  const auto& ub = b.at("sample_displacements_mm");
  EXPECT_EQ(ua.size(), ub.size());
  for (std::size_t i = 0; i < ua.size() && i < ub.size(); ++i) {
    double norm = 0.0;
    for (int c = 0; c < 3; ++c) {
      const double x = ua[i][c].get<double>(), y = ub[i][c].get<double>();
      difference = std::max(difference, std::abs(x - y));
      norm += x * x;
    }
    largest = std::max(largest, std::sqrt(norm));
  }
  return difference / largest;
}

TEST(VerifyFemMpi, TwoProcessesSolveEachLevelAsOneDoes) {
  const fs::path root = fs::temp_directory_path() / ("tissue_test_verify_fem_mpi_" + std::to_string(::getpid()));
  const fs::path alone = root / "one", together = root / "two";
  const tissue_test::TissueRun one = run_tissue(study_arguments(alone));
  ASSERT_EQ(one.exit_code, 0) << one.output;
  const tissue_test::TissueRun two =
      run_command(std::string(TISSUE_MPIEXEC) + " " + TISSUE_BINARY + " " + study_arguments(together));
  ASSERT_EQ(two.exit_code, 0) << two.output;
  // Rank 0 alone prints: the study's table once, not once per process.
  std::size_t tables = 0;
  for (std::size_t at = two.output.find("## Mesh convergence: lung_small_ci"); at != std::string::npos;
       at = two.output.find("## Mesh convergence: lung_small_ci", at + 1))
    ++tables;
  EXPECT_EQ(tables, 1u) << two.output;

  const nlohmann::json a = read_levels(alone), b = read_levels(together);
  ASSERT_EQ(a.size(), 2u);
  ASSERT_EQ(b.size(), 2u);
  for (std::size_t l = 0; l < a.size(); ++l) {
    EXPECT_EQ(a[l].at("mpi_processes").get<int>(), 1);
    EXPECT_EQ(b[l].at("mpi_processes").get<int>(), 2);
    EXPECT_EQ(a[l].at("n_dofs").get<long>(), b[l].at("n_dofs").get<long>()) << "level " << l;  // the same mesh
    const double difference = relative_difference(a[l], b[l]);
    std::cout << a[l].at("mesh_size_mm").get<double>() << " mm: " << a[l].at("n_dofs").get<long>()
              << " DOFs, largest sample difference between one and two processes (relative) " << difference << "\n";
    // Newton stops at the case's 1e-8, where the two runs' GMRES paths leave different last iterates.
    EXPECT_LT(difference, 2e-9) << "level " << l;  // 3.0e-10 and 4.4e-10 when this was written
  }
  std::ifstream md(together / "fem.md");
  const std::string text((std::istreambuf_iterator<char>(md)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("The lung levels were solved on 2 MPI processes"), std::string::npos) << text;

  // Any other command refuses to run as N copies side by side, naming those that run distributed.
  const tissue_test::TissueRun refused = run_command(std::string(TISSUE_MPIEXEC) + " " + TISSUE_BINARY +
                                                     " case check " + TISSUE_TEST_CONFIG_DIR + "/ci/lung_small_ci.json");
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.output.find("only `tissue solve fem`, `tissue solve meshless` and `tissue verify fem` run under "
                                "mpirun"),
            std::string::npos)
      << refused.output;
  fs::remove_all(root);
}

}  // namespace
