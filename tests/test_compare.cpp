// The comparator (`tissue compare`) on data with known answers: the eq. 34 RMSE, the flags of samples on the
// load-patch edge or near the cut (distances in closed form), the reference's error bar from a mesh study,
// summary.json / samples.csv / table.md, the sweep row, the radar script, and the command's error contract.
// The whole command on the lung runs in the accuracy gates (test_compare_accuracy.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "experiments/comparator/compare.hpp"
#include "experiments/comparator/compare_metrics.hpp"
#include "experiments/io/child_process.hpp"
#include "experiments/comparator/mesh_study_estimate.hpp"
#include "tests/tissue_process.hpp"

namespace fs = std::filesystem;
using nlohmann::json;
using experiments::estimate_remaining_error;
using experiments::MeshStudyEstimate;

namespace {

using RunResult = tissue_test::TissueRun;
RunResult run(const std::string& args) { return tissue_test::run_tissue(args); }

fs::path temp_dir(const std::string& tag) {
  const fs::path d = fs::temp_directory_path() / ("tissue_compare_" + tag + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

TEST(CompareMetrics, RmseIsEq34) {
  Eigen::MatrixXd u(3, 3), ref(3, 3);
  ref << 1, 0, 0, 0, 2, 0, 0, 0, 3;
  u << 1, 0, 3, 0, 2, 0, 4, 0, 3;  // errors 3, 0, 4
  EXPECT_NEAR(experiments::rmse(u, ref), std::sqrt((9.0 + 0.0 + 16.0) / 3.0), 1e-15);
  EXPECT_NEAR(experiments::rmse(u, ref, {true, true, false}), std::sqrt(9.0 / 2.0), 1e-15);
  EXPECT_TRUE(std::isnan(experiments::rmse(u, ref, {false, false, false})));
  EXPECT_NEAR(experiments::peak_magnitude(u), 5.0, 1e-15);  // |(4, 0, 3)|
}

TEST(CompareMetrics, FlagsSamplesOnThePatchEdgeAndNearTheCut) {
  const Eigen::Vector3d centre(0, 0, 0);
  const double radius = 0.012;
  // Points in the plane z = 0 at 5, 11.5, 12, 14 and 30 mm from the centre.
  Eigen::MatrixXd points(5, 3);
  points << 0.005, 0, 0, 0, 0.0115, 0, -0.012, 0, 0, 0, -0.014, 0, 0.030, 0, 0;
  // A vertical cut: the segment x = 0.030 ... 0.040 at y = 0.005, swept 20 mm down from z = 0.
  const core::RuledSurface cut({{0.030, 0.005, 0.0}, {0.040, 0.005, 0.0}}, Eigen::Vector3d(0, 0, -1), 0.020);
  experiments::SampleFlagRules rules;
  rules.patch_edge_distance = 0.001;
  rules.cut_distance = 0.010;
  const auto d = experiments::diagnose_samples(points, centre, radius, cut, rules);
  const std::array<double, 5> edge{0.007, 0.0005, 0.0, 0.002, 0.018};
  for (std::size_t i = 0; i < 5; ++i) EXPECT_NEAR(d.edge_distance[i], edge[i], 1e-15) << i;
  EXPECT_EQ(d.on_patch_edge, (std::vector<bool>{false, true, true, false, false}));
  // Distance to the cut: the last point lies 5 mm from the cut plane, on the segment's end.
  EXPECT_NEAR(*d.cut_distance[4], 0.005, 1e-15);
  EXPECT_NEAR(*d.cut_distance[0], std::hypot(0.025, 0.005), 1e-15);
  EXPECT_EQ(d.near_cut, (std::vector<bool>{false, false, false, false, true}));
  EXPECT_EQ(d.num_flagged(), 3u);
  EXPECT_EQ(d.unflagged_mask(), (std::vector<bool>{true, false, false, true, false}));

  const auto no_cut = experiments::diagnose_samples(points, centre, radius, std::nullopt, rules);
  EXPECT_FALSE(no_cut.cut_distance[4].has_value());
  EXPECT_EQ(no_cut.num_flagged(), 2u);
}

/// A `tissue verify fem` result with one case studied at 20/16/12 mm.
json study_json(const Eigen::MatrixXd& finest_mm, bool with_order) {
  json levels = json::array();
  for (double h : {20.0, 16.0, 12.0}) {
    json samples = json::array();
    for (Eigen::Index i = 0; i < finest_mm.rows(); ++i)
      samples.push_back({finest_mm(i, 0) * (h == 12.0 ? 1.0 : 1.01), finest_mm(i, 1), finest_mm(i, 2)});
    levels.push_back({{"mesh_size_mm", h}, {"sample_displacements_mm", samples}});
  }
  json richardson = with_order ? json{{"observed_order", 1.8}, {"estimated_error_of_finest_relative", 0.02}}
                               : json{{"note", "differences not decreasing"}, {"assumed_order", 1.0},
                                      {"estimated_error_of_finest_relative", 0.03}};
  return {{"mesh_convergence", {{"lung_small", {{"levels", levels}, {"richardson", richardson}}}}}};
}

TEST(CompareMetrics, ExtrapolatedSamplesCarryTheFinestLevelsBar) {
  Eigen::MatrixXd u_mm(2, 3);
  u_mm << 3, 0, 4, 0, 0, 0;
  json study = study_json(u_mm, true);
  study["mesh_convergence"]["lung_small"]["richardson"]["extrapolated_sample_displacements_mm"] =
      json::array({{3.3, 0.0, 4.4}, {0.0, 0.0, 0.0}});  // ‖x‖ = 5.5 mm
  const auto bar = experiments::reference_error_bar(study, "fem.json", "lung_small", 0.012, u_mm * 1e-3);
  ASSERT_TRUE(bar.known) << bar.why_unknown;
  ASSERT_TRUE(bar.extrapolated_samples.has_value());
  EXPECT_NEAR((*bar.extrapolated_samples)(0, 0), 3.3e-3, 1e-15);
  EXPECT_NEAR((*bar.extrapolated_samples)(0, 2), 4.4e-3, 1e-15);
  // The finest level's estimated error (2 % of 5 mm = 0.1 mm), relative to the extrapolated samples' norm.
  EXPECT_NEAR(bar.extrapolated_relative, 0.1 / 5.5, 1e-12);
  EXPECT_NE(bar.extrapolated_method.find("finest level's (12 mm) estimated error"), std::string::npos)
      << bar.extrapolated_method;
  // A study without them (written before they were) gives none.
  EXPECT_FALSE(experiments::reference_error_bar(study_json(u_mm, true), "fem.json", "lung_small", 0.012, u_mm * 1e-3)
                   .extrapolated_samples.has_value());
}

TEST(CompareMetrics, ReferenceErrorBarOnlyForTheStudiedSolve) {
  Eigen::MatrixXd u_mm(2, 3);
  u_mm << 3, 0, 4, 0, 0, 0;  // ‖U‖ = 5 mm over n = 2 samples
  const json study = study_json(u_mm, true);
  const auto bar = experiments::reference_error_bar(study, "fem.json", "lung_small", 0.012, u_mm * 1e-3);
  ASSERT_TRUE(bar.known) << bar.why_unknown;
  EXPECT_NEAR(bar.relative, 0.02, 1e-15);
  EXPECT_NEAR(bar.rms_mm, 0.02 * 5.0 / std::sqrt(2.0), 1e-12);
  EXPECT_NE(bar.method.find("observed order 1.80"), std::string::npos) << bar.method;

  const auto bound = experiments::reference_error_bar(study_json(u_mm, false), "fem.json", "lung_small", 0.012, u_mm * 1e-3);
  ASSERT_TRUE(bound.known);
  EXPECT_NEAR(bound.rms_mm, 0.03 * 5.0 / std::sqrt(2.0), 1e-12);
  EXPECT_EQ(bound.method, "differences not decreasing");

  // A coarser level of the study: its distance to the finest (1 % of the x components: 0.03 mm, 0.6 % of its
  // ‖U‖ = 5.018 mm) plus the finest level's 2 % of 5 mm.
  Eigen::MatrixXd coarse_mm = u_mm;
  coarse_mm.col(0) *= 1.01;
  const auto coarse = experiments::reference_error_bar(study, "fem.json", "lung_small", 0.016, coarse_mm * 1e-3);
  ASSERT_TRUE(coarse.known) << coarse.why_unknown;
  EXPECT_NEAR(coarse.rms_mm, (0.03 + 0.02 * 5.0) / std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(coarse.relative, (0.03 + 0.1) / coarse_mm.norm(), 1e-12);
  EXPECT_NE(coarse.method.find("finest level, 12 mm (0.60 % of this reference)"), std::string::npos) << coarse.method;
  EXPECT_NE(coarse.method.find("observed order 1.80"), std::string::npos) << coarse.method;

  auto b = experiments::reference_error_bar(study, "fem.json", "lung_small", 0.024, u_mm * 1e-3);
  EXPECT_FALSE(b.known);
  EXPECT_NE(b.why_unknown.find("no level at 24 mm, this reference's mesh size (its finest level is 12 mm)"),
            std::string::npos)
      << b.why_unknown;
  b = experiments::reference_error_bar(study, "fem.json", "lung_small", 0.016, u_mm * 1e-3);  // not the 16 mm solve
  EXPECT_FALSE(b.known);
  EXPECT_NE(b.why_unknown.find("16 mm samples differ"), std::string::npos) << b.why_unknown;
  b = experiments::reference_error_bar(study, "fem.json", "lung_large", 0.012, u_mm * 1e-3);
  EXPECT_FALSE(b.known);
  EXPECT_NE(b.why_unknown.find("no mesh study of case 'lung_large'"), std::string::npos) << b.why_unknown;
  Eigen::MatrixXd other = u_mm * 1e-3;
  other(0, 0) *= 1.001;
  b = experiments::reference_error_bar(study, "fem.json", "lung_small", 0.012, other);
  EXPECT_FALSE(b.known);
  EXPECT_NE(b.why_unknown.find("solved another case or build"), std::string::npos) << b.why_unknown;
}

experiments::ModelResult result_with(const Eigen::MatrixXd& u, double total_seconds) {
  experiments::ModelResult r;
  r.sample_displacements = u;
  r.total_seconds = total_seconds;
  r.setup_seconds = 0.5;
  r.steps.push_back({1, 1.0, total_seconds, 0.25, 0.75, 3, {1e-9}, 0});
  return r;
}

experiments::Comparison synthetic_comparison(bool identical_variants) {
  experiments::Comparison c;
  c.case_name = "synthetic";
  c.config = "synthetic.json";
  c.sample_points.resize(3, 3);
  c.sample_points << 0.005, 0, 0, 0.012, 0, 0, 0.030, 0, 0;
  Eigen::MatrixXd ref(3, 3), a(3, 3), b(3, 3);
  ref << 0.004, 0, 0, 0.002, 0, 0, 0.001, 0, 0;  // peak 4 mm
  a << 0.004, 0, 0.0003, 0.002, 0.0004, 0, 0.001, 0, 0;
  b = identical_variants ? a : ref * 0.5;
  c.reference = result_with(ref, 10.0);
  c.models = {{"enrichment", result_with(a, 4.0)}, {"visibility", result_with(b, 5.0)}};
  c.models[0].second.role = "proposed: the synthetic proposed model";
  c.models[1].second.role = "baseline: the synthetic baseline";
  c.rules.patch_edge_distance = 0.001;
  c.rules.cut_distance = 0.010;
  c.diagnostics =
      experiments::diagnose_samples(c.sample_points, Eigen::Vector3d::Zero(), 0.012, std::nullopt, c.rules);
  c.geometry_seconds = 2.0;
  c.has_cut = true;
  return c;
}

/// Three levels of a study whose samples converge exactly as u(h) = u* + c h^p (ratio 1.5 between levels, the
/// coarsest at `coarsest_mm`).
std::vector<Eigen::MatrixXd> converging_levels(double order, double coarsest_mm = 27.0) {
  Eigen::MatrixXd exact(2, 3), c(2, 3);
  exact << 1.0, 2.0, 3.0, -1.0, 0.5, 2.0;
  c << 0.3, -0.2, 0.1, 0.05, 0.2, -0.1;
  std::vector<Eigen::MatrixXd> u;
  for (double h_mm : {coarsest_mm, coarsest_mm / 1.5, coarsest_mm / 2.25})
    u.push_back(exact + std::pow(h_mm / 100.0, order) * c);
  return u;
}

TEST(MeshStudyEstimate, RichardsonRecoversTheExactErrorAtTheExpectedOrder) {
  for (double order : {1.0, 2.0}) {
    const std::vector<Eigen::MatrixXd> u = converging_levels(order);
    Eigen::MatrixXd exact(2, 3);
    exact << 1.0, 2.0, 3.0, -1.0, 0.5, 2.0;
    const double true_error = (u[2] - exact).norm() / u[2].norm();
    const MeshStudyEstimate e = estimate_remaining_error(u, {27, 18, 12}, order);
    ASSERT_TRUE(e.json.contains("observed_order")) << e.json.dump();
    EXPECT_EQ(e.json["kind"], "richardson");
    EXPECT_NEAR(e.json["observed_order"].get<double>(), order, 1e-9);
    EXPECT_NEAR(e.json["estimated_error_of_finest_relative"].get<double>(), true_error, 1e-9 * true_error);
    // Within the tolerance of the expected order it is still Richardson with the observed one.
    EXPECT_EQ(estimate_remaining_error(u, {27, 18, 12}, order + 0.25).json["kind"], "richardson");
  }
}

// fem.md's hint: only a study of one mesh per level outside the band is told that its order may be the noise's.
TEST(MeshStudyEstimate, OnlyAnOrderOutsideTheBandFromOneMeshPerLevelGetsTheAveragingHint) {
  const MeshStudyEstimate outside = estimate_remaining_error(converging_levels(1.0), {27, 18, 12}, 2.0);
  ASSERT_EQ(outside.json["kind"], "assumed_order");
  EXPECT_NE(one_mesh_per_level_hint(outside, 1).find("--meshes-per-level 3"), std::string::npos);
  EXPECT_EQ(one_mesh_per_level_hint(outside, 3), "");
  const MeshStudyEstimate inside = estimate_remaining_error(converging_levels(2.0), {27, 18, 12}, 2.0);
  ASSERT_EQ(inside.json["kind"], "richardson");
  EXPECT_EQ(one_mesh_per_level_hint(inside, 1), "");
}

TEST(MeshStudyEstimate, AnOrderFarFromTheExpectedOneIsReportedAndNotExtrapolated) {
  // Order 0.2 (a coarse level not yet asymptotic) where 1 is expected: extrapolating with it would give 6x the
  // estimate at the expected order.
  const std::vector<Eigen::MatrixXd> slow = converging_levels(0.2);
  const MeshStudyEstimate e = estimate_remaining_error(slow, {27, 18, 12}, 1.0);
  const double d2 = (slow[2] - slow[1]).norm() / slow[2].norm();
  EXPECT_FALSE(e.json.contains("observed_order"));
  EXPECT_EQ(e.json["kind"], "assumed_order");
  EXPECT_NEAR(e.json["observed_order_not_used"].get<double>(), 0.2, 1e-9);
  EXPECT_EQ(e.json["assumed_order"].get<double>(), 1.0);
  EXPECT_NEAR(e.json["estimated_error_of_finest_relative"].get<double>(), d2 / 0.5, 1e-12);
  EXPECT_NE(e.sentence.find("observed order 0.20 below the expected 1"), std::string::npos) << e.sentence;
  EXPECT_NE(e.sentence.find("not a bound"), std::string::npos) << e.sentence;
  // Order 2 where 1 is expected: not used either, since it would shrink the bar (d2 / 3.5 instead of d2 / 0.5).
  const std::vector<Eigen::MatrixXd> fast = converging_levels(2.0);
  const MeshStudyEstimate f = estimate_remaining_error(fast, {27, 18, 12}, 1.0);
  EXPECT_EQ(f.json["kind"], "assumed_order");
  EXPECT_NE(f.sentence.find("above the expected 1"), std::string::npos) << f.sentence;
  EXPECT_NEAR(f.json["estimated_error_of_finest_relative"].get<double>(),
              (fast[2] - fast[1]).norm() / fast[2].norm() / 0.5, 1e-12);
  // Order 1 where 2 is expected (samples within an element of the load patch's edge): the observed order, which
  // gives the larger bar (d2 / 0.5 instead of d2 / 1.25).
  const std::vector<Eigen::MatrixXd> first = converging_levels(1.0);
  const MeshStudyEstimate o = estimate_remaining_error(first, {27, 18, 12}, 2.0);
  EXPECT_EQ(o.json["kind"], "assumed_order");
  EXPECT_NEAR(o.json["assumed_order"].get<double>(), 1.0, 1e-9);
  EXPECT_NEAR(o.json["estimated_error_of_finest_relative"].get<double>(),
              (first[2] - first[1]).norm() / first[2].norm() / 0.5, 1e-9);
  // Differences that grow: the same estimate, no order.
  std::vector<Eigen::MatrixXd> growing = {slow[0], slow[0] + 0.01 * slow[0], slow[0] + 0.05 * slow[0]};
  const MeshStudyEstimate g = estimate_remaining_error(growing, {27, 18, 12}, 1.0);
  EXPECT_FALSE(g.json.contains("observed_order_not_used"));
  EXPECT_NE(g.json["note"].get<std::string>().find("differences not decreasing"), std::string::npos);
  // Two equal finest levels, and too few levels.
  EXPECT_EQ(estimate_remaining_error({slow[0], slow[1], slow[1]}, {27, 18, 12}, 1.0).json["note"],
            "the last two levels agree exactly");
  EXPECT_TRUE(estimate_remaining_error({slow[0], slow[1]}, {27, 18}, 1.0).json.is_null());
}

TEST(MeshStudyEstimate, FourLevelsReportTheOrderOfEachThree) {
  std::vector<Eigen::MatrixXd> u = converging_levels(2.0);  // 27, 18, 12 mm
  ASSERT_EQ(u.size(), 3u);
  const std::vector<Eigen::MatrixXd> coarse = converging_levels(2.0, 40.5);  // 40.5, 27, 18 mm
  u.insert(u.begin(), coarse.front());
  const MeshStudyEstimate e = estimate_remaining_error(u, {40.5, 27, 18, 12}, 2.0);
  ASSERT_EQ(e.json["observed_orders"].size(), 2u) << e.json.dump();
  for (const auto& p : e.json["observed_orders"]) EXPECT_NEAR(p.get<double>(), 2.0, 1e-9);
}

// A graded load patch refines the samples within its ball like h^2 and those beyond like h, so the study's levels
// hold two groups converging at different orders; one order over all rows mixes them (2.6 on lung_large between the
// 2 and 3 of its groups), and each group's own rows give back its order.
TEST(MeshStudyEstimate, EachGroupOfSamplesGivesItsOwnOrder) {
  const std::vector<double> h_mm{40.5, 27, 18, 12};
  Eigen::MatrixXd exact(3, 3), c(3, 3);
  exact << 1.0, 2.0, 3.0, -1.0, 0.5, 2.0, 0.2, 0.1, -0.3;
  c << 0.3, -0.2, 0.1, 0.05, 0.2, -0.1, -0.4, 0.1, 0.2;
  std::vector<Eigen::MatrixXd> u;
  for (double h : h_mm) {
    Eigen::MatrixXd level = exact;
    level.row(0) += 10.0 * std::pow(h / 100.0, 3.0) * c.row(0);  // within the ball: order 3, larger at these h
    level.row(1) += std::pow(h / 100.0, 2.0) * c.row(1);  // beyond it: order 2
    level.row(2) += std::pow(h / 100.0, 2.0) * c.row(2);
    u.push_back(level);
  }
  const std::vector<double> within = experiments::observed_orders(u, h_mm, {0});
  const std::vector<double> beyond = experiments::observed_orders(u, h_mm, {1, 2});
  ASSERT_EQ(within.size(), 2u);
  ASSERT_EQ(beyond.size(), 2u);
  for (double p : within) EXPECT_NEAR(p, 3.0, 1e-9);
  for (double p : beyond) EXPECT_NEAR(p, 2.0, 1e-9);
  // All rows: the mix, between the two and falling toward the lower order as h falls (2.902, then 2.804), as
  // estimate_remaining_error reports it.
  const std::vector<double> all = experiments::observed_orders(u, h_mm, {0, 1, 2});
  ASSERT_EQ(all.size(), 2u);
  EXPECT_NEAR(all[0], 2.902, 1e-3);
  EXPECT_NEAR(all[1], 2.804, 1e-3);
  const MeshStudyEstimate e = estimate_remaining_error(u, h_mm, 2.0);
  for (std::size_t l = 0; l < all.size(); ++l) EXPECT_NEAR(all[l], e.json["observed_orders"][l].get<double>(), 1e-12);
}

TEST(MeshStudyEstimate, ExpectedOrderIsTheRoughestLinesOrTheFacetedSurfaces) {
  const std::string configs = TISSUE_TEST_CONFIG_DIR;
  // lung_small: tapered elastic support, patch edge graded like h^2 (order 4), P2 (3): the faceted surface's 2.
  core::Case small = core::load_case(configs + "/lung_small.json");
  EXPECT_EQ(experiments::expected_sample_order(small), 2.0);
  small.fem.degree = 1;
  EXPECT_EQ(experiments::expected_sample_order(small), 2.0);
  small.fixed_region.taper = 0.0;  // k_s jumps at the support's edge: order 2
  EXPECT_EQ(experiments::expected_sample_order(small), 2.0);
  // lung_large: the crack's front graded like h^g gives g.
  core::Case large = core::load_case(configs + "/lung_large.json");
  EXPECT_EQ(experiments::expected_sample_order(large), 2.0);
  large.geometry.crack_front_grading = 1.5;
  EXPECT_EQ(experiments::expected_sample_order(large), 1.5);
  large.geometry.crack_front_grading = 1.0;
  EXPECT_EQ(experiments::expected_sample_order(large), 1.0);
  large.geometry.crack_front_grading = 3.0;  // beyond the surface's 2
  EXPECT_EQ(experiments::expected_sample_order(large), 2.0);
  EXPECT_EQ(experiments::expected_sample_order(core::load_case(configs + "/lung_small_clamp.json")), 1.0);
}

TEST(CompareSummary, EachModelsCutEffectAgainstTheFems) {
  experiments::Comparison c = synthetic_comparison(false);
  Eigen::MatrixXd fem_effect = Eigen::MatrixXd::Zero(3, 3), enr_effect = fem_effect, vis_effect = fem_effect;
  fem_effect(0, 0) = 1e-3;  // the FEM's cut opens sample 0 by 1 mm
  enr_effect(0, 0) = 0.9e-3;
  vis_effect(0, 0) = 1.5e-3;
  vis_effect(2, 1) = 0.2e-3;
  c.uncut_samples = {{"fem", c.reference.sample_displacements - fem_effect},
                     {"enrichment", c.models[0].second.sample_displacements - enr_effect},
                     {"visibility", c.models[1].second.sample_displacements - vis_effect}};
  const json e = experiments::comparison_summary(c)["cut_effect"];
  EXPECT_NEAR(e["fem_peak_effect_mm"].get<double>(), 1.0, 1e-12);
  EXPECT_NEAR(e["models"]["enrichment"]["rmse_mm"].get<double>(), std::sqrt(0.01 / 3.0), 1e-12);
  EXPECT_NEAR(e["models"]["visibility"]["rmse_mm"].get<double>(), std::sqrt((0.25 + 0.04) / 3.0), 1e-12);
  EXPECT_NEAR(e["models"]["visibility"]["rmse_relative_to_fem_peak"].get<double>(), std::sqrt(0.29 / 3.0), 1e-12);
  EXPECT_NEAR(e["models"]["visibility"]["peak_effect_mm"].get<double>(), 1.5, 1e-12);
  // No uncut solves (no cut, or --no-cut-effect): no such entry.
  EXPECT_FALSE(experiments::comparison_summary(synthetic_comparison(false)).contains("cut_effect"));
}

// With the solved reference and a study that extrapolated it, every model is also scored against the extrapolated
// samples, with their own bar; with the extrapolated reference (or without a study) there is no such section.
TEST(CompareSummary, EachModelAgainstTheExtrapolatedSamplesBesideTheirBar) {
  experiments::Comparison c = synthetic_comparison(false);
  EXPECT_FALSE(experiments::comparison_summary(c).contains("versus_extrapolated"));  // no study
  Eigen::MatrixXd x = c.reference.sample_displacements;
  x(0, 0) = 0.005;  // the converged FEM: 5 mm at sample 0, 1 mm more than this reference
  c.error_bar.known = true;
  c.error_bar.rms_mm = 0.7;
  c.error_bar.extrapolated_samples = x;
  c.error_bar.extrapolated_relative = 0.01;
  const json v = experiments::comparison_summary(c)["versus_extrapolated"];
  const double norm_mm = std::sqrt(25.0 + 4.0 + 1.0);
  EXPECT_NEAR(v["peak_sample_displacement_mm"].get<double>(), 5.0, 1e-12);
  EXPECT_NEAR(v["error_bar_mm"].get<double>(), 0.01 * norm_mm / std::sqrt(3.0), 1e-12);
  EXPECT_NEAR(experiments::comparison_summary(c)["reference"]["solved_minus_extrapolated_rms_mm"].get<double>(),
              std::sqrt(1.0 / 3.0), 1e-12);
  // enrichment errors against x: (-1, 0, 0.3), (0, 0.4, 0), 0 mm; visibility = half the reference: 3, 1, 0.5 mm.
  EXPECT_NEAR(v["models"]["enrichment"]["rmse_mm"].get<double>(), std::sqrt((1.09 + 0.16) / 3.0), 1e-12);
  EXPECT_NEAR(v["models"]["visibility"]["rmse_mm"].get<double>(), std::sqrt((9.0 + 1.0 + 0.25) / 3.0), 1e-12);
  EXPECT_NEAR(v["models"]["visibility"]["rmse_relative_to_peak"].get<double>(), std::sqrt(10.25 / 3.0) / 5.0, 1e-12);
  const std::string md = experiments::comparison_table_md(c, experiments::comparison_summary(c));
  EXPECT_NE(md.find("**Against the converged FEM**"), std::string::npos);
  // The extrapolated reference already is what this section would add.
  c.solved_reference_samples = c.reference.sample_displacements;
  c.reference.sample_displacements = x;
  EXPECT_FALSE(experiments::comparison_summary(c).contains("versus_extrapolated"));
}

TEST(CompareSummary, RmseWithAndWithoutFlaggedSamplesAndPhaseTimes) {
  const experiments::Comparison c = synthetic_comparison(false);
  const json s = experiments::comparison_summary(c);
  // enrichment errors: 0.3, 0.4, 0 mm; sample 1 sits on the patch edge (12 mm from the centre).
  EXPECT_EQ(s["flagged_samples"], json::array({1}));
  const json& e = s["models"]["enrichment"];
  EXPECT_NEAR(e["rmse_mm"].get<double>(), std::sqrt((0.09 + 0.16) / 3.0), 1e-12);
  EXPECT_NEAR(e["rmse_unflagged_mm"].get<double>(), std::sqrt(0.09 / 2.0), 1e-12);
  EXPECT_NEAR(e["rmse_relative_to_peak"].get<double>(), std::sqrt((0.09 + 0.16) / 3.0) / 4.0, 1e-12);
  EXPECT_EQ(e["n_unflagged"], 2);
  EXPECT_NEAR(e["max_sample_error_mm"].get<double>(), 0.4, 1e-12);
  EXPECT_NEAR(e["timings"]["assembly_seconds"].get<double>(), 0.25, 1e-15);
  EXPECT_NEAR(e["timings"]["solve_seconds"].get<double>(), 0.75, 1e-15);
  EXPECT_NEAR(e["timings"]["total_seconds"].get<double>(), 4.0, 1e-15);
  EXPECT_TRUE(e["reference_error_bar_mm"].is_null());
  // visibility = half the reference: errors 2, 1, 0.5 mm.
  const double vis = std::sqrt((4.0 + 1.0 + 0.25) / 3.0);
  EXPECT_NEAR(s["models"]["visibility"]["rmse_mm"].get<double>(), vis, 1e-12);
  EXPECT_NEAR(s["difference_mm"].get<double>(), std::sqrt(0.25 / 3.0) - vis, 1e-12);
  EXPECT_NEAR(s["reference"]["peak_sample_displacement_mm"].get<double>(), 4.0, 1e-12);
  EXPECT_NEAR(s["geometry_seconds"].get<double>(), 2.0, 1e-15);
  EXPECT_FALSE(s.contains("warning"));

  // The sweep row takes its figures from the summary.
  const auto& columns = experiments::compare_row_columns();
  const auto values = experiments::compare_row_values(s);
  ASSERT_EQ(columns.size(), values.size());
  const auto value = [&](const std::string& name) {
    return values[static_cast<std::size_t>(std::find(columns.begin(), columns.end(), name) - columns.begin())];
  };
  EXPECT_NEAR(std::stod(value("enrichment_rmse_mm")), std::sqrt(0.25 / 3.0), 1e-8);
  EXPECT_NEAR(std::stod(value("visibility_rmse_mm")), vis, 1e-8);
  EXPECT_EQ(value("n_flagged"), "1");
  EXPECT_EQ(value("fem_error_bar_mm"), "");
  EXPECT_EQ(value("fem_seconds"), "10");
}

// A sweep reads each run's summary.json into its row from a worker thread: a summary cut short or written by another
// version gives empty cells, never an exception (or a read of a missing key, which nlohmann leaves undefined).
TEST(CompareSummary, SweepRowOfAnIncompleteSummaryIsEmptyCells) {
  const auto& columns = experiments::compare_row_columns();
  for (const json& s : {json::object(), json::array(), json("text"), json{{"n_samples", 3}, {"models", 1}}}) {
    const auto values = experiments::compare_row_values(s);
    ASSERT_EQ(values.size(), columns.size()) << s.dump();
    const std::size_t filled = static_cast<std::size_t>(
        std::count_if(values.begin(), values.end(), [](const std::string& v) { return !v.empty(); }));
    EXPECT_EQ(filled, s.is_object() && s.contains("n_samples") ? 1u : 0u) << s.dump();
  }
}

TEST(CompareSummary, IdenticalVariantsOnACutCaseAreReported) {
  const json s = experiments::comparison_summary(synthetic_comparison(true));
  ASSERT_TRUE(s.contains("warning"));
  EXPECT_NE(s["warning"].get<std::string>().find("identical sample displacements"), std::string::npos);
  EXPECT_EQ(s["variants_max_sample_difference_mm"].get<double>(), 0.0);
}

TEST(CompareSummary, SamplesCsvHasOneRowPerSampleAndModel) {
  const experiments::Comparison c = synthetic_comparison(false);
  std::istringstream csv(experiments::comparison_samples_csv(c));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line,
            "sample,model,x_mm,y_mm,z_mm,ux_mm,uy_mm,uz_mm,magnitude_mm,error_to_reference_mm,edge_distance_mm,"
            "cut_distance_mm,on_patch_edge,near_cut,flagged");
  std::vector<std::string> rows;
  while (std::getline(csv, line)) rows.push_back(line);
  ASSERT_EQ(rows.size(), 9u);
  EXPECT_EQ(rows[0], "0,fem,5.000000,0.000000,0.000000,4,0,0,4,,7.000000,,0,0,0");
  EXPECT_EQ(rows[1], "0,enrichment,5.000000,0.000000,0.000000,4,0,0.3,4.01123422,0.3,7.000000,,0,0,0");
  EXPECT_EQ(rows[4], "1,enrichment,12.000000,0.000000,0.000000,2,0.4,0,2.03960781,0.4,0.000000,,1,0,1");
  const std::string md = experiments::comparison_table_md(c, experiments::comparison_summary(c));
  EXPECT_NE(md.find("| enrichment | 0.2887 | 7.2 % | 0.2121 | 5.3 % | unknown | 0.4000 | 4.0 |"), std::string::npos)
      << md;
}

TEST(CompareCommand, HelpAndBadInput) {
  for (const char* sub : {"compare", "sweep", "rsr"}) {
    const RunResult r = run(std::string(sub) + " --help");
    EXPECT_EQ(r.exit_code, 0) << sub << r.output;
    EXPECT_NE(r.output.find("Usage"), std::string::npos) << sub;
  }
  const fs::path dir = temp_dir("bad");
  std::ifstream in(std::string(TISSUE_TEST_CONFIG_DIR) + "/ci/lung_small_ci.json");
  json c = json::parse(in);
  c["material"]["K1"] = -1;
  std::ofstream(dir / "bad.json") << c.dump(2);
  const RunResult r = run("compare " + (dir / "bad.json").string() + " --out " + (dir / "out" / "x").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("bad.json: /material/K1: expected a number > 0"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out")) << "a failed compare must leave nothing behind";
  // A --reference-family study of another case is refused before any solve, naming the file and what was expected.
  const RunResult family = run("compare " + std::string(TISSUE_TEST_CONFIG_DIR) + "/ci/lung_small_ci.json --out " +
                               (dir / "out" / "y").string() + " --reference-family " + std::string(TISSUE_SOURCE_DIR) +
                               "/results/verify/one_rate/lung_small/fem.json");
  EXPECT_EQ(family.exit_code, 2) << family.output;
  EXPECT_NE(family.output.find("one_rate/lung_small/fem.json: /mesh_convergence/lung_small_ci: a mesh study of case "
                               "'lung_small_ci' was expected"),
            std::string::npos)
      << family.output;
  EXPECT_EQ(family.output.find("FEM step"), std::string::npos) << family.output;
  EXPECT_FALSE(fs::exists(dir / "out")) << "a failed compare must leave nothing behind";
  fs::remove_all(dir);
}

TEST(RadarScript, DrawsAPngFromSamplesCsv) {
  const fs::path dir = temp_dir("radar");
  const experiments::Comparison c = synthetic_comparison(false);
  std::ofstream(dir / "samples.csv") << experiments::comparison_samples_csv(c);
  const auto p = experiments::run_process({experiments::plot_python(), std::string(TISSUE_SOURCE_DIR) + "/scripts/plot_radar.py",
                                           (dir / "samples.csv").string(), (dir / "radar.png").string(), "--title", "t"},
                                          (dir / "log").string());
  std::ifstream log(dir / "log");
  const std::string text((std::istreambuf_iterator<char>(log)), std::istreambuf_iterator<char>());
  if (!p.ok() && text.find("No module named 'matplotlib'") != std::string::npos)
    GTEST_SKIP() << "python3-matplotlib is not installed (scripts/install_dependencies.sh installs it)";
  ASSERT_TRUE(p.ok()) << p.error << "\n" << text;
  std::ifstream png(dir / "radar.png", std::ios::binary);
  std::array<char, 8> magic{};
  png.read(magic.data(), magic.size());
  EXPECT_EQ(std::string(magic.data() + 1, 3), "PNG");
  fs::remove_all(dir);
}

}  // namespace
