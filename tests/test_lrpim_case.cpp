// The LRPIM model on a load case (meshless/lrpim/lrpim_case.hpp, docs/LRPIM.md §5): a bar held at one end by the
// case's elastic support (a Robin term) or clamp and pulled by the case's load patch at the other, against its closed
// form, with both linear solvers; the load's total force; the refusal of a cut case. The case and its geometry are
// built in code (the box mesh's boundary tagged as the geometry pipeline tags a lung), so no Gmsh run is needed.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <limits>

#include "core/case.hpp"
#include "core/case_error.hpp"
#include "core/geometry.hpp"
#include "experiments/models/model_registry.hpp"
#include "meshless/lrpim/lrpim_case.hpp"
#include "meshless/lrpim/lrpim_verification.hpp"
#include "meshless/verification/box_mesh.hpp"

namespace meshless::lrpim {
namespace {

constexpr double kLength = 0.04, kSide = 0.01, kStress = 100.0, kSupport = 2.0e5;

// A 40 x 10 x 10 mm bar, 8 x 2 x 2 cells (5 mm nodes): the x = 0 end fixed, the x = L end the load patch, the
// rest free. nu = 0, so the uniaxial stress state is exact in 3-D; k = 1 as the lung cases. The force is held
// from t = 0 (ramp 0) over 10 steps of 20 s, so the creep (relaxation time 1 s) has settled at the last step.
void bar_case(core::FixedRegionSpec::Support support, core::Case* c, core::Geometry* g) {
  c->name = "lrpim bar";
  c->source_file = "bar.json";
  c->material.K1 = 6000.0;
  c->material.K2 = 12000.0;
  c->material.eta = 18000.0;
  c->material.nu = 0.0;
  c->material.k = 1.0;
  c->fixed_region.kind = core::FixedRegionSpec::Kind::near_plane;
  c->fixed_region.point = Eigen::Vector3d::Zero();
  c->fixed_region.normal = Eigen::Vector3d::UnitX();
  c->fixed_region.distance = 1e-3;
  c->fixed_region.support = support;
  c->fixed_region.stiffness = kSupport;
  c->load.force = Eigen::Vector3d(kStress * kSide * kSide, 0.0, 0.0);
  c->load.ramp_time = 0.0;
  c->time.total = 200.0;
  c->time.steps = 10;
  c->meshless.node_spacing = 0.005;
  g->meshless_mesh = make_box_mesh(
      Eigen::Vector3d::Zero(), Eigen::Vector3d(kLength, kSide, kSide), 8, 2, 2,
      [](const Eigen::Vector3d& centroid, const Eigen::Vector3d&) {
        if (centroid.x() < 1e-9) return core::FaceTag::fixed;
        if (centroid.x() > kLength - 1e-9) return core::FaceTag::load;
        return core::FaceTag::free_surface;
      },
      0.15, 3);
  g->sample_points.resize(4, 3);
  g->sample_points << kLength, 0.5 * kSide, 0.5 * kSide, kLength, 0.0, kSide, 0.5 * kLength, 0.3 * kSide, 0.0,
      0.0, 0.7 * kSide, 0.2 * kSide;
}

// The steady state of the Kelvin law under the held uniaxial stress: N = sigma / E_inf, eps = (sqrt(1 + 4kN) - 1)/2k
// (docs/MATERIAL.md §1.2); the support adds the rigid shift sigma / k_s (t = -k_s u on the x = 0 end).
Eigen::Vector3d exact_displacement(const core::Case& c, const Eigen::Vector3d& x) {
  const double n = kStress / c.material.equilibrium_modulus(), k = c.material.k;
  const double eps = (std::sqrt(1.0 + 4.0 * k * n) - 1.0) / (2.0 * k);
  const double shift = c.fixed_region.support == core::FixedRegionSpec::Support::elastic ? kStress / kSupport : 0.0;
  return Eigen::Vector3d(shift + eps * x.x(), 0.0, 0.0);
}

double run_bar(core::FixedRegionSpec::Support support, LrpimLinearSolver solver, LrpimCaseRun* out = nullptr) {
  core::Case c;
  core::Geometry g;
  bar_case(support, &c, &g);
  LrpimCaseOptions options;
  options.linear_solver = solver;
  options.newton_tolerance = 1e-12;
  const LrpimCaseRun run = run_lrpim_case(c, g, options);
  EXPECT_EQ(run.steps.size(), 10u);
  double worst = 0.0;
  const double peak = exact_displacement(c, Eigen::Vector3d(kLength, 0, 0)).norm();
  for (Eigen::Index i = 0; i < g.sample_points.rows(); ++i) {
    const Eigen::Vector3d u = run.sample_displacements.row(i).transpose();
    worst = std::max(worst, (u - exact_displacement(c, g.sample_points.row(i).transpose())).norm() / peak);
  }
  if (out) *out = run;
  return worst;
}

TEST(LrpimCase, ElasticallySupportedBarMatchesTheClosedForm) {
  LrpimCaseRun run;
  const double mumps = run_bar(core::FixedRegionSpec::Support::elastic, LrpimLinearSolver::mumps, &run);
  const double sparse_lu = run_bar(core::FixedRegionSpec::Support::elastic, LrpimLinearSolver::sparse_lu);
  const double krylov = run_bar(core::FixedRegionSpec::Support::elastic, LrpimLinearSolver::petsc_krylov);
  std::cout << "elastic support: samples off the closed form by " << mumps << " (MUMPS), " << sparse_lu
            << " (SparseLU), " << krylov << " (PETSc GMRES + ILU) of the tip displacement; " << run.n_nodes << " nodes, "
            << run.details["points"].dump() << ", factorisations " << run.details["factorisations"] << "\n";
  // A linear field in a linear-reproducing model with the divergence correction: round-off and Newton's 1e-12.
  EXPECT_LT(mumps, 1e-12);      // 8.4e-14
  EXPECT_LT(sparse_lu, 1e-12);  // 8.6e-14
  EXPECT_LT(krylov, 1e-10);
  // The load's total force is the case's: traction (force / this cloud's load-patch area) times that area.
  EXPECT_NEAR(run.details["load"]["total_force_n"][0].get<double>(), kStress * kSide * kSide, 1e-15);
  EXPECT_NEAR(run.details["load"]["patch_area_m2"].get<double>(), kSide * kSide, 1e-18);
  EXPECT_EQ(run.details["constrained_nodes"].get<int>(), 0);  // the support is a natural condition
  EXPECT_GT(run.details["points"]["elastic_support"].get<int>(), 0);
  for (const LrpimStepReport& s : run.steps) EXPECT_LE(s.residuals.back(), 1e-12) << "step " << s.step;
  // The six balance equations are imposed (the body hangs on its support alone), and a linear field balances
  // already: the fictitious body force that imposes them is round-off.
  const nlohmann::json& bc = run.details["balance_correction_mn"];
  EXPECT_TRUE(bc["active"].get<bool>());
  for (int k = 0; k < 3; ++k) EXPECT_LT(std::abs(bc["net_force"][k].get<double>()), 1e-9 * 1e3 * kStress * kSide * kSide);
}

TEST(LrpimCase, ClampedBarMatchesTheClosedForm) {
  LrpimCaseRun run;
  const double worst = run_bar(core::FixedRegionSpec::Support::clamp, LrpimLinearSolver::mumps, &run);
  std::cout << "clamp: samples off the closed form by " << worst << " of the tip displacement; "
            << run.details["constrained_nodes"] << " nodes held\n";
  EXPECT_LT(worst, 1e-12);  // 1.3e-13
  EXPECT_EQ(run.details["constrained_nodes"].get<int>(), 9);  // the 3 x 3 nodes of the x = 0 end
  EXPECT_GT(run.details["points"]["reaction"].get<int>(), 0);
}

// The bar on its elastic support bent by a transverse load of a tenth of the axial one's, k = 0, one step.
void bent_bar_case(core::Case* c, core::Geometry* g) {
  bar_case(core::FixedRegionSpec::Support::elastic, c, g);
  c->load.force = Eigen::Vector3d(0.0, 0.0, 0.1 * kStress * kSide * kSide);
  c->material.k = 0.0;
  c->time.steps = 1;
}

// The bent bar under the nonlinear law (k = 1) over `steps` steps: the restart and load-series tests' case.
void nonlinear_bent_bar_case(int steps, core::Case* c, core::Geometry* g) {
  bent_bar_case(c, g);
  c->material.k = 1.0;
  c->time.steps = steps;
}

// The sum of all local equations against the body's balance (LrpimTestFunction, docs/LRPIM.md §5): the bar on its
// elastic support bent by a transverse load, whose stress varies so that the clipped spheres' quadrature does not
// integrate it exactly. With the plain spline the v_i do not sum to 1 and the support's reaction misses the load;
// with the Shepard-normalised splines they do, and what is left is the quadrature's error.
TEST(LrpimCase, ShepardTestFunctionsBalanceTheNetForceOfABentBar) {
  auto imbalance = [](LrpimTestFunction test, int polar) {  // of the local equations alone
    core::Case c;
    core::Geometry g;
    bent_bar_case(&c, &g);
    LrpimCaseOptions options;
    options.test_function = test;
    options.balance_rigid_modes = false;
    options.rule.polar = polar, options.rule.azimuthal = 2 * polar;
    options.linear_solver = LrpimLinearSolver::sparse_lu;
    const LrpimCaseRun run = run_lrpim_case(c, g, options);
    const nlohmann::json& b = run.details["global_balance_mn"];
    Eigen::Vector3d applied, support;
    for (int k = 0; k < 3; ++k) applied[k] = b["applied_force"][k], support[k] = b["support_force"][k];
    return (applied + support).norm() / applied.norm();
  };
  // The shipped rule (8 polar x 16 azimuthal directions) and a finer one (16 x 32): the spline's imbalance is the
  // test functions' (it stays), the Shepard functions' is the quadrature's (it falls with the rule).
  const double spline = imbalance(LrpimTestFunction::spline, 8), spline_fine = imbalance(LrpimTestFunction::spline, 16);
  const double shepard = imbalance(LrpimTestFunction::shepard, 8), shepard_fine = imbalance(LrpimTestFunction::shepard, 16);
  std::cout << "|net force of the support's reaction and the load| / |load|: spline " << spline << " (finer rule "
            << spline_fine << "), Shepard " << shepard << " (finer rule " << shepard_fine << ")\n";
  // Measured: 0.0699, 0.0837, 0.0245, 0.00577.
  EXPECT_NEAR(spline, 0.0699, 0.002);
  EXPECT_GT(spline_fine, 0.075);
  EXPECT_NEAR(shepard, 0.0245, 0.001);
  EXPECT_LT(shepard_fine, 0.0062);
}

// LrpimProblem::balance_rigid_modes on the bent bar above: the support's reaction now cancels the load's net force
// and moment to round-off (on global_balance's own rule, an independent check of the bordered solve), and the
// fictitious body force that does it is what the local equations left out of balance: about the Shepard
// imbalance above, and it falls with the rule as that does.
TEST(LrpimCase, BalanceEquationsHoldTheBentBarsRigidMotion) {
  struct Result {
    double force_imbalance, moment_imbalance, correction;
  };
  auto run_bent = [](int polar) {
    core::Case c;
    core::Geometry g;
    bent_bar_case(&c, &g);
    LrpimCaseOptions options;
    options.rule.polar = polar, options.rule.azimuthal = 2 * polar;
    options.linear_solver = LrpimLinearSolver::sparse_lu;
    options.newton_tolerance = 1e-12;
    const LrpimCaseRun run = run_lrpim_case(c, g, options);
    const nlohmann::json& b = run.details["global_balance_mn"];
    const nlohmann::json& bc = run.details["balance_correction_mn"];
    Eigen::Vector3d fa, fs, ma, ms, fc;
    for (int k = 0; k < 3; ++k)
      fa[k] = b["applied_force"][k], fs[k] = b["support_force"][k], ma[k] = b["applied_moment_mn_m"][k],
      ms[k] = b["support_moment_mn_m"][k], fc[k] = bc["net_force"][k];
    EXPECT_TRUE(bc["active"].get<bool>());
    return Result{(fa + fs).norm() / fa.norm(), (ma + ms).norm() / ma.norm(), fc.norm() / fa.norm()};
  };
  const Result shipped = run_bent(8), fine = run_bent(16);
  std::cout << "with the balance equations: force imbalance " << shipped.force_imbalance << ", moment imbalance "
            << shipped.moment_imbalance << ", correction " << shipped.correction << " of the load (finer rule: "
            << fine.force_imbalance << ", " << fine.moment_imbalance << ", " << fine.correction << ")\n";
  EXPECT_LT(shipped.force_imbalance, 1e-10);
  EXPECT_LT(shipped.moment_imbalance, 1e-10);
  EXPECT_LT(fine.moment_imbalance, 1e-10);
  // Measured: 0.0269 and 0.00665 of the load (the local equations alone: 0.0245 and 0.00577 above).
  EXPECT_NEAR(shipped.correction, 0.0269, 0.001);
  EXPECT_LT(fine.correction, 0.0070);
}

// LrpimModel::restart, which the Fig. 9 analogue uses to set a cloud up once and solve it under several forces: after a
// run under one force, a restart under another gives what a model built for that force gives, bit for bit, through
// the nonlinear law (k = 1) and the imposed balance, and the per-run statistics start again.
TEST(LrpimCase, RestartedModelSolvesAnotherForceAsANewModelWould) {
  core::Case c;
  core::Geometry g;
  nonlinear_bent_bar_case(3, &c, &g);
  core::Case heavier = c;
  heavier.load.force *= 2.0;
  for (const LrpimLinearSolver solver : {LrpimLinearSolver::mumps, LrpimLinearSolver::sparse_lu}) {
    LrpimCaseOptions options;
    options.linear_solver = solver;
    const LrpimCaseRun fresh = run_lrpim_case(heavier, g, options);

    LrpimModel model(lrpim_problem_from_case(c, g, options));
    const LrpimCaseRun first = run_lrpim_model(model, c, g);
    model.restart(lrpim_load_from_case(heavier, g));
    EXPECT_EQ(model.statistics().factorisations, 0);
    EXPECT_TRUE(model.steps().empty());
    const LrpimCaseRun again = run_lrpim_model(model, heavier, g);
    const double peak = fresh.sample_displacements.rowwise().norm().maxCoeff();
    const double first_peak = first.sample_displacements.rowwise().norm().maxCoeff();
    const double difference = (again.sample_displacements - fresh.sample_displacements).cwiseAbs().maxCoeff();
    std::cout << "restart (" << (solver == LrpimLinearSolver::mumps ? "MUMPS" : "SparseLU") << "): peak sample "
              << 1e3 * peak << " mm (first force " << 1e3 * first_peak << " mm); largest difference to a new model "
              << difference << " m\n";
    EXPECT_GT(peak, 1.8 * first_peak);  // the second force was solved, not the first one's state kept
    EXPECT_EQ(difference, 0.0);
    ASSERT_EQ(again.steps.size(), fresh.steps.size());
    for (std::size_t i = 0; i < fresh.steps.size(); ++i) {
      EXPECT_EQ(again.steps[i].newton_iterations, fresh.steps[i].newton_iterations) << "step " << i + 1;
      EXPECT_EQ(again.steps[i].residuals, fresh.steps[i].residuals) << "step " << i + 1;
    }
    EXPECT_EQ(again.details["balance_correction_mn"], fresh.details["balance_correction_mn"]);
  }
}

// The meshless models as the Fig. 9 analogue times them (experiments::Model::prepare_load_series): one set-up, then
// each force's solve on it, with the samples of the model's own solve of that force bit for bit (each force
// factorises its own tangent), and no set-up charged to the solve. The heavier force first: each run reports its own
// closest approach to the law's limit, not the series' (EfgModel::restart).
TEST(LrpimCase, LoadSeriesOfEachMeshlessModelSetsUpOnceAndSolvesEachForceAsItsOwnSolve) {
  core::Case c;
  core::Geometry g;
  nonlinear_bent_bar_case(2, &c, &g);
  for (const char* name : {"lrpim", "enrichment"}) {
    const std::unique_ptr<experiments::Model> model = experiments::make_model(name);
    ASSERT_NE(model, nullptr) << name;
    const std::unique_ptr<experiments::LoadSeries> series = model->prepare_load_series(c, g);
    EXPECT_GT(series->setup_seconds(), 0.0) << name;
    for (const double factor : {2.0, 0.5}) {
      core::Case at = c;
      at.load.force *= factor;
      const experiments::ModelResult own = model->solve(at, g, {});
      const experiments::ModelResult in_series = series->solve(at, {});
      EXPECT_EQ((in_series.sample_displacements - own.sample_displacements).cwiseAbs().maxCoeff(), 0.0)
          << name << " at " << factor << " x the force";
      EXPECT_EQ(in_series.setup_seconds, 0.0) << name;
      EXPECT_GT(own.setup_seconds, 0.0) << name;
      EXPECT_EQ(in_series.steps.size(), own.steps.size()) << name;
      if (own.details.contains("law_admissibility"))
        EXPECT_EQ(in_series.details["law_admissibility"], own.details["law_admissibility"]) << name << " " << factor;
    }
  }
}

// LrpimCaseOptions::min_node_separation (docs/LRPIM.md §6): the LRPIM's nodes keep the asked distance from each other,
// and every node left out lies within it of a kept one, so the cloud loses no region; 0 keeps the cloud as it is.
TEST(LrpimCase, NodeSeparationKeepsNoTwoNodesCloserThanAsked) {
  core::Case c;
  core::Geometry g;
  bar_case(core::FixedRegionSpec::Support::elastic, &c, &g);
  const core::PointMatrix& cloud = g.meshless_mesh.vertices;
  LrpimCaseOptions options;
  EXPECT_EQ(lrpim_problem_from_case(c, g, options).nodes, cloud);
  options.min_node_separation = 0.9;
  const core::PointMatrix kept = lrpim_problem_from_case(c, g, options).nodes;
  const double d = 0.9 * c.meshless.node_spacing;
  double closest_kept = std::numeric_limits<double>::infinity(), farthest_dropped = 0.0;
  for (Eigen::Index i = 0; i < kept.rows(); ++i)
    for (Eigen::Index j = i + 1; j < kept.rows(); ++j) closest_kept = std::min(closest_kept, (kept.row(i) - kept.row(j)).norm());
  for (Eigen::Index i = 0; i < cloud.rows(); ++i) {
    double nearest_kept = std::numeric_limits<double>::infinity();
    for (Eigen::Index j = 0; j < kept.rows(); ++j) nearest_kept = std::min(nearest_kept, (cloud.row(i) - kept.row(j)).norm());
    farthest_dropped = std::max(farthest_dropped, nearest_kept);
  }
  std::cout << "separation " << 1e3 * d << " mm: " << kept.rows() << " of " << cloud.rows() << " nodes kept, closest pair "
            << 1e3 * closest_kept << " mm, farthest node left out " << 1e3 * farthest_dropped << " mm from a kept one\n";
  EXPECT_LT(kept.rows(), cloud.rows());
  EXPECT_GE(closest_kept, d);
  EXPECT_LT(farthest_dropped, d);
}

TEST(LrpimCase, CutCaseIsRefusedWithWhatToDo) {
  core::Case c;
  core::Geometry g;
  bar_case(core::FixedRegionSpec::Support::elastic, &c, &g);
  c.cut = core::CutSpec{};
  try {
    run_lrpim_case(c, g);
    FAIL() << "a cut case must be refused";
  } catch (const core::CaseError& e) {
    EXPECT_EQ(e.json_path(), "/cut");
    EXPECT_NE(std::string(e.what()).find("no crack treatment"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("remove /cut"), std::string::npos) << e.what();
  }
}

TEST(LrpimVerification, QuickSetPassesAndReportsEveryFigure) {
  // What `tissue verify lrpim --quick` reports (meshless/lrpim/lrpim_verification.hpp).
  const nlohmann::json v = run_lrpim_verification(true);
  std::cout << v.dump(1) << "\n";
  EXPECT_TRUE(v["quick"].get<bool>());
  for (const char* item : {"rpim_invariants", "patch_test_box", "patch_test_cloud_surface", "cantilever",
                           "creep_bar_k0", "creep_bar_k2"})
    EXPECT_TRUE(v[item]["passed"].get<bool>()) << item << ": " << v[item].dump();
  EXPECT_TRUE(v["passed"].get<bool>());
  EXPECT_GT(v["patch_test_uncorrected"]["displacement"].get<double>(), 1e-4);  // the correction is what passes it
  EXPECT_EQ(v["cantilever"]["levels"].size(), 2u);
}

}  // namespace
}  // namespace meshless::lrpim
