// The reference's error bar against mesh studies of the same problem in another mesh family
// (experiments/comparator/mesh_family_error_bar.hpp): the meshes beside each level are averaged, the bar is the
// reference's distance to the family's finest level plus that level's Richardson estimate, and a study of another
// problem, a mesh far from every level or other samples are refused, saying which.
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Core>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/case.hpp"
#include "experiments/comparator/mesh_family_error_bar.hpp"

namespace fs = std::filesystem;
using nlohmann::json;
using experiments::MeshFamily;
using experiments::MeshFamilyError;

namespace {

const std::string kCaseFile = std::string(TISSUE_SOURCE_DIR) + "/configs/lung_small.json";

fs::path temp_dir(const std::string& tag) {
  const fs::path d = fs::temp_directory_path() / ("tissue_mesh_family_" + tag + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

json rows_mm(const Eigen::MatrixXd& m) {
  json rows = json::array();
  for (Eigen::Index i = 0; i < m.rows(); ++i) rows.push_back({m(i, 0) * 1e3, m(i, 1) * 1e3, m(i, 2) * 1e3});
  return rows;
}

/// The exact samples U, the discretisation error's shape C (u_h = U + C h^2, h in mm) and each mesh's own noise
/// N_k cos h (k = 0, +1, -1: they sum to zero, so the mean of a level's three meshes is U + C h^2 exactly) [m].
struct Synthetic {
  Eigen::MatrixXd points{4, 3}, exact{4, 3}, shape{4, 3};
  Eigen::MatrixXd noise[3];
  Synthetic() {
    points << 0.01, 0.02, 0.03, -0.02, 0.0, 0.01, 0.0, 0.015, -0.01, 0.03, -0.01, 0.0;
    exact << 2e-3, 1e-4, 3e-3, 1.5e-3, -2e-4, 2.5e-3, 1e-3, 3e-4, 2.7e-3, 1.8e-3, 0.0, 2.2e-3;
    shape = Eigen::MatrixXd::Constant(4, 3, 1e-8);
    shape(0, 2) = -3e-8;
    noise[0] = Eigen::MatrixXd::Constant(4, 3, 2e-7);
    noise[1] = Eigen::MatrixXd::Constant(4, 3, -1e-7);
    noise[1](2, 0) = 4e-7;
    noise[2] = -noise[0] - noise[1];
  }
  /// The noise differs from level to level (cos h), as a non-nested mesh's does.
  Eigen::MatrixXd mesh(double nominal_mm, int k) const {
    return exact + shape * nominal_mm * nominal_mm + noise[k] * std::cos(nominal_mm);
  }
};

/// A fem.json of `verify fem` holding one study of case_name: config, the sample points and one level per
/// (size, samples).
void write_study(const fs::path& file, const std::string& config, const Eigen::MatrixXd& points,
                 const std::vector<std::pair<double, Eigen::MatrixXd>>& levels, const std::string& case_name = "lung_small") {
  json study = {{"config", config}, {"sample_points_mm", rows_mm(points)}, {"levels", json::array()}};
  for (const auto& [size, u] : levels)
    study["levels"].push_back({{"mesh_size_mm", size}, {"sample_displacements_mm", rows_mm(u)}});
  std::ofstream(file) << json{{"mesh_convergence", {{case_name, study}}}}.dump(2);
}

/// The shipped case with another mesh family: only /geometry/refinement and /description differ.
std::string write_family_case(const fs::path& dir, const std::function<void(json&)>& change = {}) {
  json doc = core::load_case(kCaseFile).document;
  doc["geometry"]["refinement"]["load_patch_grading_zone"] = "edge";
  doc["description"] = "the one-rate family of lung_small";
  if (change) change(doc);
  const fs::path file = dir / "family_case.json";
  std::ofstream(file) << doc.dump(2);
  return file.string();
}

constexpr double kNominal[] = {27.0, 18.0, 12.0, 8.0};  // one ratio, 1.5

/// Study A: the nominal meshes (k = 0); study B: the meshes 1 % on either side (k = +1, -1).
std::vector<std::string> write_family(const fs::path& dir, const Synthetic& s, const std::string& config) {
  std::vector<std::pair<double, Eigen::MatrixXd>> a, b;
  for (double h : kNominal) {
    a.emplace_back(h, s.mesh(h, 0));
    b.emplace_back(h * 1.01, s.mesh(h, 1));
    b.emplace_back(h * 0.99, s.mesh(h, 2));
  }
  write_study(dir / "a.json", config, s.points, a);
  write_study(dir / "b.json", config, s.points, b);
  return {(dir / "a.json").string(), (dir / "b.json").string()};
}

TEST(MeshFamily, AveragesTheMeshesBesideEachLevelAndMeasuresTheBarAgainstItsFinest) {
  const fs::path dir = temp_dir("bar");
  const Synthetic s;
  const core::Case c = core::load_case(kCaseFile);
  const MeshFamily family = experiments::read_mesh_family(write_family(dir, s, write_family_case(dir)), c);
  ASSERT_EQ(family.means.size(), 4u);
  EXPECT_EQ(family.meshes, (std::vector<int>{3, 3, 3, 3}));
  EXPECT_EQ(family.h_mm, (std::vector<double>{27, 18, 12, 8}));
  EXPECT_EQ(family.expected_order, 2.0);
  // The noise cancels in the means, which converge at order 2 exactly: Richardson in the band, exact extrapolation.
  EXPECT_NEAR((family.means.back() - (s.exact + 64.0 * s.shape)).norm(), 0.0, 1e-15);
  EXPECT_EQ(family.estimate.json["kind"], "richardson") << family.estimate.json.dump();
  EXPECT_NEAR(family.estimate.json["observed_order"].get<double>(), 2.0, 1e-9);  // 1e-15 reached

  // A reference of another mesh: the exact samples plus an offset D.
  Eigen::MatrixXd offset = Eigen::MatrixXd::Constant(4, 3, 5e-6);
  offset(1, 1) = -2e-5;
  const Eigen::MatrixXd u_h = s.exact + offset;
  const experiments::ReferenceErrorBar bar = experiments::error_bar_against_family(family, s.points, u_h);
  ASSERT_TRUE(bar.known);
  // ||U_h - U_f|| + ||U_f - U||, U_f = U + 64 C, as an RMS per sample in mm.
  const double expected = ((u_h - family.means.back()).norm() + (64.0 * s.shape).norm()) * 1e3 / 2.0;
  EXPECT_NEAR(bar.rms_mm, expected, 1e-9 * expected);
  ASSERT_TRUE(bar.extrapolated_samples.has_value());
  EXPECT_NEAR((*bar.extrapolated_samples - s.exact).norm(), 0.0, 1e-9 * (64.0 * s.shape).norm());
  EXPECT_NEAR(bar.extrapolated_rms_mm(), (64.0 * s.shape).norm() * 1e3 / 2.0, 1e-9 * expected);
  EXPECT_NE(bar.method.find("8 mm, the mean of 3 meshes"), std::string::npos) << bar.method;
  EXPECT_NE(bar.method.find("observed order 2.00"), std::string::npos) << bar.method;
  EXPECT_NE(bar.source.find("b.json"), std::string::npos) << bar.source;

  // Without the meshes beside it, study A's own noise reaches its order: another estimate.
  const MeshFamily one_mesh = experiments::read_mesh_family({(dir / "a.json").string()}, c);
  EXPECT_EQ(one_mesh.meshes, (std::vector<int>{1, 1, 1, 1}));
  EXPECT_GT(std::abs(one_mesh.estimate.json.value("observed_order", one_mesh.estimate.json.value(
                                                                      "observed_order_not_used", 0.0)) - 2.0),
            0.01)
      << one_mesh.estimate.json.dump();
}

TEST(MeshFamily, OnlyTheDiscretisationMayDiffer) {
  json a = core::load_case(kCaseFile).document, b = a;
  b["description"] = "another text";
  b["geometry"]["mesh_size"] = 5.3;
  b["geometry"]["refinement"]["load_patch_grading"] = 1.0;
  b["fem"]["degree"] = 3;
  b["meshless"]["node_spacing"] = 3.0;
  EXPECT_EQ(experiments::first_problem_difference(a, b), "");
  b["material"]["k"] = 0.0;
  EXPECT_EQ(experiments::first_problem_difference(a, b), "/material/k");

  const fs::path dir = temp_dir("problem");
  const Synthetic s;
  const std::string config = write_family_case(dir, [](json& doc) { doc["load"]["force"][2] = -0.6; });
  try {
    experiments::read_mesh_family(write_family(dir, s, config), core::load_case(kCaseFile));
    FAIL() << "a study of another load was accepted";
  } catch (const MeshFamilyError& e) {
    EXPECT_NE(std::string(e.what()).find("a.json: its case"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("at /load/force"), std::string::npos) << e.what();
  }
}

TEST(MeshFamily, RefusesAMeshFarFromEveryLevelTooFewLevelsAndOtherSamples) {
  const fs::path dir = temp_dir("refuse");
  const Synthetic s;
  const core::Case c = core::load_case(kCaseFile);
  const std::string config = write_family_case(dir);
  const std::vector<std::string> files = write_family(dir, s, config);
  write_study(dir / "far.json", config, s.points, {{10.0, s.mesh(10.0, 0)}});  // 17 % from 12 mm
  try {
    experiments::read_mesh_family({files[0], (dir / "far.json").string()}, c);
    FAIL() << "a 10 mm mesh was averaged into a level";
  } catch (const MeshFamilyError& e) {
    EXPECT_NE(std::string(e.what()).find("a mesh of 10 mm lies more than 5 % from every level"), std::string::npos)
        << e.what();
  }
  // The meshes beside the levels given first: their levels pair up 2 % apart, which is no family of levels.
  try {
    experiments::read_mesh_family({files[1], files[0]}, c);
    FAIL() << "a study of pairs of meshes 2 % apart was taken for the family's levels";
  } catch (const MeshFamilyError& e) {
    EXPECT_NE(std::string(e.what()).find("lie within 5 % of each other"), std::string::npos) << e.what();
  }
  write_study(dir / "two.json", config, s.points, {{18.0, s.mesh(18.0, 0)}, {12.0, s.mesh(12.0, 0)}});
  EXPECT_THROW(experiments::read_mesh_family({(dir / "two.json").string()}, c), MeshFamilyError);
  write_study(dir / "other_case.json", config, s.points, {{18.0, s.mesh(18.0, 0)}}, "lung_large");
  EXPECT_THROW(experiments::read_mesh_family({(dir / "other_case.json").string()}, c), MeshFamilyError);

  const MeshFamily family = experiments::read_mesh_family(files, c);
  Eigen::MatrixXd moved = s.points;
  moved(3, 2) += 1e-6;  // 1 µm
  EXPECT_THROW(experiments::check_family_sample_points(family, moved), MeshFamilyError);
  EXPECT_NO_THROW(experiments::check_family_sample_points(family, s.points));
}

}  // namespace
