// The model interface and its registry (experiments/models/): the names a case may list in /compare, the roles the
// tables print, the refusals of a bad list, the floor model's RMSE (the reference's own RMS displacement), and the
// sweep's columns, one group per scored model.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/case.hpp"
#include "core/case_error.hpp"
#include "experiments/comparator/compare.hpp"
#include "experiments/models/model_registry.hpp"
#include "experiments/models/efg/meshless_runs.hpp"
#include "core/kelvin_law.hpp"
#include "core/ruled_surface.hpp"

namespace {

using nlohmann::json;

json shipped_case() {
  std::ifstream in(std::string(TISSUE_TEST_CONFIG_DIR) + "/lung_small.json");
  return json::parse(in);
}

/// The CaseError parse_case, or the model list, raises for `document`, as "path: message".
std::string refusal(const json& document) {
  try {
    const core::Case c = core::parse_case(document, "case.json");
    experiments::models_of_case(c);
  } catch (const core::CaseError& e) {
    return e.json_path() + ": " + e.what();
  }
  return "accepted";
}

TEST(ModelRegistry, KnowsEveryModelByNameWithItsRole) {
  const std::vector<std::string> names = experiments::registered_model_names();
  for (const char* name : {"fem", "enrichment", "visibility", "paper", "lrpim", "zero"})
    EXPECT_NE(std::find(names.begin(), names.end(), name), names.end()) << name;
  EXPECT_EQ(experiments::make_model("no such model"), nullptr);
  EXPECT_EQ(experiments::role_kind(experiments::make_model("fem")->role()), "reference");
  EXPECT_EQ(experiments::role_kind(experiments::make_model("enrichment")->role()), "proposed");
  EXPECT_EQ(experiments::role_kind(experiments::make_model("visibility")->role()), "baseline");
  EXPECT_EQ(experiments::role_kind(experiments::make_model("zero")->role()), "floor");
  EXPECT_EQ(experiments::role_kind(experiments::make_model("paper")->role()), "as published");
  for (const auto& name : names) {
    const auto m = experiments::make_model(name);
    EXPECT_EQ(m->name(), name);
    EXPECT_FALSE(m->description().empty()) << name;
  }
}

TEST(ModelRegistry, TheDefaultListIsTheReferenceAndThePapersTwoVariants) {
  json doc = shipped_case();
  doc.erase("compare");  // the shipped case adds the floor; without /compare the default list
  const core::Case c = core::parse_case(doc, "lung_small.json");
  const auto models = experiments::models_of_case(c);
  ASSERT_EQ(models.size(), 3u);
  EXPECT_EQ(models[0]->name(), "fem");
  EXPECT_EQ(models[1]->name(), "enrichment");
  EXPECT_EQ(models[2]->name(), "visibility");
  // Without a cut the two variants are one model, solved once; with a cut they differ.
  EXPECT_EQ(models[2]->same_as(c), "enrichment");
  EXPECT_EQ(models[1]->same_as(c), "");
  json cut = shipped_case();
  std::ifstream in(std::string(TISSUE_TEST_CONFIG_DIR) + "/lung_large.json");
  const core::Case cut_case = core::parse_case(json::parse(in), std::string(TISSUE_TEST_CONFIG_DIR) + "/lung_large.json");
  ASSERT_TRUE(cut_case.cut.has_value());
  EXPECT_EQ(models[2]->same_as(cut_case), "");
  // The LRPIM model has no treatment of a cut: it says so, and solves the uncut case.
  const auto lrpim = experiments::make_model("lrpim");
  EXPECT_EQ(lrpim->cannot_solve(c), "");
  EXPECT_NE(lrpim->cannot_solve(cut_case).find("no treatment of a cut"), std::string::npos);
  EXPECT_TRUE(lrpim->needs_node_cloud());
  EXPECT_FALSE(lrpim->needs_fem_mesh());
}

// The "paper" preset is the paper's EFG as published: no VCI and no front transition, every other key kept. The
// "paper" model solves any case that way, and is the proposed model itself when the case already uses the preset.
TEST(PaperPreset, SetsThePapersConfigurationAndRefusesKeysThatContradictIt) {
  json doc = shipped_case();
  doc["meshless"]["front_transition"] = 2.0;
  const core::Case ours = core::parse_case(doc, "lung_small.json");
  EXPECT_EQ(ours.meshless.preset, core::MeshlessSpec::Preset::standard);
  EXPECT_TRUE(ours.meshless.variationally_consistent);
  EXPECT_DOUBLE_EQ(ours.meshless.front_transition, 2e-3);

  doc["meshless"].erase("front_transition");
  doc["meshless"]["preset"] = "paper";
  const core::Case paper = core::parse_case(doc, "lung_small.json");
  EXPECT_EQ(paper.meshless.preset, core::MeshlessSpec::Preset::paper);
  EXPECT_EQ(paper.meshless.preset_name(), "paper");
  EXPECT_FALSE(paper.meshless.variationally_consistent);
  EXPECT_EQ(paper.meshless.front_transition, 0.0);
  // Everything else is the case's own.
  EXPECT_DOUBLE_EQ(paper.meshless.node_spacing, ours.meshless.node_spacing);
  EXPECT_EQ(paper.meshless.quadrature_order, ours.meshless.quadrature_order);
  EXPECT_DOUBLE_EQ(paper.meshless.support_factor, ours.meshless.support_factor);
  EXPECT_EQ(paper.meshless.enrichment, ours.meshless.enrichment);
  // The translation carries the quadrature's consistency into the discrete problem.
  const auto ours_as_paper = ours.meshless.in_paper_configuration();
  EXPECT_FALSE(ours_as_paper.variationally_consistent);
  EXPECT_EQ(ours_as_paper.front_transition, 0.0);

  doc["meshless"]["front_transition"] = 2.0;
  EXPECT_EQ(refusal(doc), "/meshless/front_transition: case.json: /meshless/front_transition: expected 0 or no "
                          "key: /meshless/preset \"paper\" is the paper's enrichment (eqs. 29-32) without a front "
                          "transition");
  doc["meshless"]["front_transition"] = 0.0;  // agrees with the preset
  EXPECT_EQ(refusal(doc), "accepted");
  doc["meshless"]["variationally_consistent"] = true;
  EXPECT_EQ(refusal(doc), "/meshless/variationally_consistent: case.json: /meshless/variationally_consistent: "
                          "expected false or no key: /meshless/preset \"paper\" is the paper's plain Gauss quadrature "
                          "of eq. 22, without variationally consistent integration");
  doc["meshless"]["variationally_consistent"] = false;
  EXPECT_EQ(refusal(doc), "accepted");
  doc["meshless"]["preset"] = "published";
  EXPECT_NE(refusal(doc).find("/meshless/preset"), std::string::npos);

  const auto model = experiments::make_model("paper");
  EXPECT_EQ(model->same_as(ours), "");
  EXPECT_EQ(model->same_as(paper), "enrichment");
  EXPECT_TRUE(model->needs_node_cloud());
}

// Beside a cut's front the EFG's strain can leave the law's range because of the enrichment's sharp front, not the
// load: the error then says so and names the key to change (and, under the paper's preset, that the preset fixes it).
TEST(EfgErrors, AnInadmissibleStrainBesideTheCutsFrontNamesTheFrontTransition) {
  const core::RuledSurface cut({Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(0.04, 0.0, 0.0)},
                               Eigen::Vector3d(0.0, 0.0, -1.0), 0.02);
  core::KelvinParameters parameters;
  parameters.K1 = 6000.0;
  parameters.K2 = 12000.0;
  parameters.eta = 18000.0;
  parameters.nu = 0.4;
  parameters.k = 1.0;
  core::Vector6 strain = core::Vector6::Zero();
  strain(0) = -0.6;  // beyond -1/(2k)
  const core::KelvinLaw law(parameters);
  const core::InadmissibleStrain beside_front("meshless (EFG) model 'test'", 1.0, Eigen::Vector3d(0.02, 0.001, -0.021),
                                              strain, law);
  const core::InadmissibleStrain far_away("meshless (EFG) model 'test'", 1.0, Eigen::Vector3d(0.02, 0.03, -0.01),
                                          strain, law);
  core::MeshlessSpec spec;
  spec.node_spacing = 0.016;
  EXPECT_EQ(experiments::front_transition_hint(beside_front, spec, cut, 0.0),
            "That point is 1.41 mm from the cut's front, within one node spacing: the enrichment closes the cut there "
            "over ℓ = 0.00 mm (/meshless/front_transition), and a sharp front concentrates the strain beside it. To "
            "stay inside the range: set /meshless/front_transition to about node_spacing / 5 = 3.2 mm, which closes "
            "the cut over that distance (docs/MESHLESS.md §5.2)");
  // With ℓ already a fifth of the spacing the advice is a longer ℓ or a smaller force, not the same ℓ again.
  EXPECT_EQ(experiments::front_transition_hint(beside_front, spec, cut, 0.0032),
            "That point is 1.41 mm from the cut's front, within one node spacing: the enrichment closes the cut there "
            "over ℓ = 3.20 mm (/meshless/front_transition), and a sharp front concentrates the strain beside it. To "
            "stay inside the range: ℓ is already at least node_spacing / 5, so lengthen it (/meshless/front_transition "
            "= 6.4 mm closes the cut over twice the distance) or lower /load/force; the cloud does not resolve the "
            "strain beside this front at this load (docs/MESHLESS.md §5.2)");
  EXPECT_EQ(experiments::front_transition_hint(far_away, spec, cut, 0.0), "");  // 30 mm from the front
  EXPECT_EQ(experiments::front_transition_hint(beside_front, spec, std::nullopt, 0.0), "");
  const std::string paper = experiments::front_transition_hint(beside_front, spec.in_paper_configuration(), cut, 0.0);
  EXPECT_NE(paper.find("fixed at 0 by /meshless/preset \"paper\""), std::string::npos) << paper;
  EXPECT_NE(paper.find("leave the paper's preset (/meshless/preset \"default\")"), std::string::npos) << paper;
}

TEST(ModelRegistry, ACaseNamesItsModelsAndBadListsAreRefusedWithThePath) {
  json doc = shipped_case();
  doc["compare"] = {{"models", {"zero", "enrichment"}}};
  const core::Case c = core::parse_case(doc, "case.json");
  const auto models = experiments::models_of_case(c);
  ASSERT_EQ(models.size(), 3u);
  EXPECT_EQ(models[1]->name(), "zero");
  EXPECT_EQ(models[2]->name(), "enrichment");

  doc["compare"] = {{"models", {"enrichment", "efg2"}}};
  std::string why = refusal(doc);
  EXPECT_NE(why.find("/compare/models/1"), std::string::npos) << why;
  EXPECT_NE(why.find("efg2"), std::string::npos) << why;
  EXPECT_NE(why.find("fem, enrichment, visibility"), std::string::npos) << why;  // names the registered models

  doc["compare"] = {{"models", {"zero", "zero"}}};
  why = refusal(doc);
  EXPECT_NE(why.find("/compare/models/1"), std::string::npos) << why;
  EXPECT_NE(why.find("listed twice"), std::string::npos) << why;

  doc["compare"] = {{"models", {"fem"}}};
  why = refusal(doc);
  EXPECT_NE(why.find("/compare/models/0"), std::string::npos) << why;
  EXPECT_NE(why.find("other than the reference"), std::string::npos) << why;

  doc["compare"] = {{"models", json::array()}};
  EXPECT_NE(refusal(doc).find("/compare/models"), std::string::npos) << refusal(doc);
  doc["compare"] = {{"models", {3}}};
  EXPECT_NE(refusal(doc).find("/compare/models/0"), std::string::npos) << refusal(doc);
  doc["compare"] = {{"reference", "nothing"}};
  EXPECT_NE(refusal(doc).find("/compare/reference"), std::string::npos) << refusal(doc);
  doc["compare"] = {{"modles", {"zero"}}};
  EXPECT_NE(refusal(doc).find("/compare/modles"), std::string::npos) << refusal(doc);
}

TEST(ZeroModel, ItsRmseIsTheReferencesOwnRmsDisplacement) {
  core::Geometry g;
  g.sample_points.resize(4, 3);
  g.sample_points << 0, 0, 0, 0.01, 0, 0, 0, 0.01, 0, 0, 0, 0.01;
  const core::Case c = core::parse_case(shipped_case(), "lung_small.json");
  experiments::ModelResult zero = experiments::make_model("zero")->solve(c, g, {});
  ASSERT_EQ(zero.sample_displacements.rows(), 4);
  EXPECT_EQ(zero.sample_displacements.cwiseAbs().maxCoeff(), 0.0);

  experiments::Comparison cmp;
  cmp.sample_points = g.sample_points;
  cmp.reference.sample_displacements.resize(4, 3);
  cmp.reference.sample_displacements << 0.003, 0.004, 0, 0, 0, 0.001, 0.002, 0, 0, 0, 0, 0;  // 5, 1, 2, 0 mm
  zero.role = experiments::make_model("zero")->role();
  cmp.models = {{"zero", zero}};
  cmp.diagnostics = experiments::diagnose_samples(g.sample_points, Eigen::Vector3d(1, 1, 1), 0.012, std::nullopt,
                                                  cmp.rules);
  const json s = experiments::comparison_summary(cmp);
  EXPECT_NEAR(s["models"]["zero"]["rmse_mm"].get<double>(), std::sqrt((25.0 + 1.0 + 4.0 + 0.0) / 4.0), 1e-12);
  EXPECT_NEAR(s["models"]["zero"]["rmse_relative_to_peak"].get<double>(), std::sqrt(30.0 / 4.0) / 5.0, 1e-12);
  EXPECT_EQ(s["models"]["zero"]["role"], "floor: the undeformed body, u = 0");
  EXPECT_FALSE(s.contains("difference_mm"));  // no proposed model and baseline

  // A model that could not solve the case, or failed, is reported with its reason, never dropped silently.
  cmp.not_solved = {{"lrpim", "Fig. 9 baseline", "the LRPIM model has no treatment of a cut"},
                    {"other", "proposed", "failed: Newton did not converge"}};
  const json t = experiments::comparison_summary(cmp);
  EXPECT_EQ(t["not_solved"]["lrpim"]["why"], "the LRPIM model has no treatment of a cut");
  const std::string md = experiments::comparison_table_md(cmp, t);
  EXPECT_NE(md.find("lrpim (Fig. 9 baseline): not solved: the LRPIM model has no treatment of a cut."), std::string::npos)
      << md;
  EXPECT_NE(md.find("other (proposed): failed: Newton did not converge."), std::string::npos) << md;
}

// A load series (the Fig. 9 analogue's solves of one cloud under several forces) takes the prepared case under another
// force, and refuses any other change with the JSON path that differs: a solve of another case on the prepared
// set-up would be silently wrong.
TEST(LoadSeries, TakesOtherForcesAndRefusesAnyOtherChangeWithItsPath) {
  core::Geometry g;
  g.sample_points.resize(2, 3);
  g.sample_points << 0, 0, 0, 0.01, 0, 0;
  const json doc = shipped_case();
  const core::Case prepared = core::parse_case(doc, "lung_small.json");
  const auto zero = experiments::make_model("zero");
  const std::unique_ptr<experiments::LoadSeries> series = zero->prepare_load_series(prepared, g);
  EXPECT_EQ(series->setup_seconds(), 0.0);  // the zero model sets up in each solve

  json other_force = doc;
  other_force["load"]["force"] = {0.1, 0.0, 0.0};
  const experiments::ModelResult r = series->solve(core::parse_case(other_force, "lung_small.json"), {});
  EXPECT_EQ(r.sample_displacements.rows(), 2);

  json other_law = doc;
  other_law["material"]["k"] = 0.5;
  try {
    series->solve(core::parse_case(other_law, "other.json"), {});
    ADD_FAILURE() << "a case with another law was solved on the prepared series";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("/material/k"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("other.json"), std::string::npos) << e.what();
  }
  json other_point = doc;
  other_point["load"]["point"][0] = other_point["load"]["point"][0].get<double>() + 1.0;
  EXPECT_THROW(experiments::check_differs_only_in_force(prepared, core::parse_case(other_point, "p.json")),
               std::invalid_argument);
}

TEST(SweepColumns, OneGroupPerScoredModelAndTheDefaultListKeepsTheDocumentedColumns) {
  const std::vector<std::string> documented{
      "n_samples",          "n_flagged",          "fem_peak_mm",       "fem_error_bar_mm",
      "enrichment_rmse_mm", "enrichment_rmse_relative",                "enrichment_rmse_unflagged_mm",
      "visibility_rmse_mm", "visibility_rmse_relative",                "visibility_rmse_unflagged_mm",
      "difference_mm",      "geometry_seconds",   "fem_seconds",       "enrichment_seconds",
      "visibility_seconds", "fem_dofs",           "meshless_nodes"};
  EXPECT_EQ(experiments::compare_row_columns(), documented);
  const auto columns = experiments::compare_row_columns({"zero", "lrpim"});
  for (const char* c : {"zero_rmse_mm", "zero_seconds", "lrpim_rmse_relative", "lrpim_rmse_unflagged_mm"})
    EXPECT_NE(std::find(columns.begin(), columns.end(), c), columns.end()) << c;
  const json summary = {{"n_samples", 2},
                        {"flagged_samples", json::array()},
                        {"reference", {{"peak_sample_displacement_mm", 3.0}}},
                        {"models", {{"zero", {{"rmse_mm", 1.5}, {"timings", nullptr}}}}}};
  const auto values = experiments::compare_row_values(summary, {"zero", "lrpim"});
  ASSERT_EQ(values.size(), columns.size());
  const auto at = [&](const std::string& name) {
    return values[static_cast<std::size_t>(std::find(columns.begin(), columns.end(), name) - columns.begin())];
  };
  EXPECT_EQ(at("zero_rmse_mm"), "1.5");
  EXPECT_EQ(at("lrpim_rmse_mm"), "");  // not in this summary: an empty cell, never a failure
  EXPECT_EQ(at("fem_peak_mm"), "3");
}

}  // namespace
