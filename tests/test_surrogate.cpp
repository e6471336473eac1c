// The force -> displacement surrogate (paper §3, eqs. 25-28): the fits recover known fields, the paper's
// Marquardt (Ceres LM) reaches the linear least-squares solution the fit computes, restarting the full model
// equals a fresh one, the query superposes the axes and flags what it was not trained on, the file refuses
// what it cannot trust, and the shipped surrogate file loads and answers. The fit's robustness to rounding is
// tests/test_surrogate_fit.cpp; the comparison with the full model at untrained forces is
// tests/test_surrogate_box.cpp (label long).
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>

#include "meshless/verification/box_mesh.hpp"
#include "meshless/efg/efg_model.hpp"
#include "experiments/studies/reproduce.hpp"
#include "meshless/surrogate/surrogate.hpp"
#include "tests/surrogate_box_case.hpp"
#include "meshless/surrogate/surrogate_builder.hpp"
#include "meshless/surrogate/surrogate_cost_functions.hpp"
#include "meshless/surrogate/surrogate_file.hpp"
#include "meshless/surrogate/surrogate_fit.hpp"

namespace meshless {
namespace {

constexpr double kMm = 1e-3;

EfgProblem box_problem() { return surrogate_box_problem(); }
core::SurrogateSpec box_spec() { return surrogate_box_spec(); }

TEST(SurrogateBasis, SubsetsMatchTheSmallerBasisAndTheFrameIsOrthonormal) {
  const SpatialBasis full(6, 3, 2, 0.1);
  EXPECT_EQ(full.size(), 28 * 4 + 2 * 10);
  for (int a = 0; a <= 6; ++a)
    for (int b = 0; b <= 3; ++b)
      for (int c = 0; c <= 2; ++c) {
        const SpatialBasis small(a, b, c, 0.1);
        const std::vector<int> cols = full.subset(a, b, c);
        ASSERT_EQ(static_cast<int>(cols.size()), small.size());
        for (int k = 0; k < small.size(); ++k) EXPECT_EQ(full.terms()[cols[k]], small.terms()[k]);
        // and the same values
        const Eigen::Vector3d x(0.3, -0.2, 0.05);
        std::vector<double> vf(full.size()), vs(small.size());
        full.evaluate(x, vf.data());
        small.evaluate(x, vs.data());
        for (int k = 0; k < small.size(); ++k) EXPECT_EQ(vf[cols[k]], vs[k]);
      }
  // The contact terms of order 1 are the regularised Kelvin solution: s (delta_ij + e_i e_j) is in their
  // span.
  const SpatialBasis kelvin(0, 0, 1, 0.1);
  const Eigen::Vector3d x(0.3, -0.2, 0.05);
  std::vector<double> v(kelvin.size());
  kelvin.evaluate(x, v.data());
  const double rho = std::sqrt(x.squaredNorm() + 0.01);
  EXPECT_DOUBLE_EQ(v[1], 0.1 / rho);                                    // s
  EXPECT_DOUBLE_EQ(v[1 + 4], 0.1 / rho * x.x() * x.x() / (rho * rho));  // s e_xi^2
  const SurfaceFrame f = SurfaceFrame::at({1, 2, 3}, {0.3, -0.2, 0.9}, 2.0, 0.5);
  EXPECT_NEAR(f.tangent1.dot(f.tangent2), 0.0, 1e-15);
  EXPECT_NEAR(f.tangent1.dot(f.normal), 0.0, 1e-15);
  EXPECT_NEAR(f.tangent1.cross(f.tangent2).dot(f.normal), 1.0, 1e-15);  // right-handed
  const Eigen::Vector3d y = f.origin + 2.0 * (0.1 * f.tangent1 - 0.4 * f.tangent2 + 0.25 * f.normal);
  EXPECT_TRUE(f.local(y).isApprox(Eigen::Vector3d(0.1, -0.4, 0.25), 1e-14));
}

TEST(SurrogateCostFunctions, ForcePolynomialRecoversACubicAndTheCrossValidationPicksItsOrder) {
  // u = 0.8 s - 0.3 s^2 + 0.05 s^3 on 8 levels: lambda = 3 reproduces it exactly; 1 and 2 cannot.
  ContactTrainingData data;
  SurfaceNodes surface;
  surface.vertex = {0};
  surface.position = core::PointMatrix::Zero(1, 3);
  surface.normal = core::PointMatrix(1, 3);
  surface.normal << 0, 0, 1;
  data.contact = 0;
  data.levels = {-4, -3, -2, -1, 1, 2, 3, 4};
  auto u = [](double f) {
    const double s = f / 4.0;
    return 1e-3 * (0.8 * s - 0.3 * s * s + 0.05 * s * s * s);
  };
  for (int j = 0; j < 3; ++j)
    for (double f : data.levels) {
      core::PointMatrix d = core::PointMatrix::Zero(1, 3);
      d(0, j) = u(f);
      data.displacement[j].push_back(d);
    }
  SurrogateFitOptions options;
  options.max_tangential_order = 0;
  options.max_normal_order = 0;
  options.max_contact_order = 0;
  options.cv_folds = 4;
  // One surface node cannot be cross-validated spatially: fit the contact node alone through the public path
  // by giving it enough copies of itself.
  surface.vertex.assign(12, 0);
  surface.position = core::PointMatrix::Zero(12, 3);
  for (int i = 0; i < 12; ++i) surface.position.row(i) << 1e-3 * (i % 4), 1e-3 * (i / 4), 0.0;
  surface.normal = core::PointMatrix::Zero(12, 3);
  surface.normal.col(2).setOnes();
  for (int j = 0; j < 3; ++j)
    for (core::PointMatrix& d : data.displacement[j]) d = d.row(0).replicate(12, 1).eval();
  const ContactFit fit = fit_contact(surface, data, 4.0, options);
  for (int j = 0; j < 3; ++j) {
    const AxisFit& a = fit.axis[j];
    EXPECT_EQ(a.force_order, 3) << "axis " << j;
    ASSERT_EQ(a.contact.cols(), 3);
    // r_p in SI: 1e-3 * coefficient / 4^p
    // Relative 1e-12. Measured 8.1e-20, 1.7e-20, 1.2e-21 (absolute).
    EXPECT_NEAR(a.contact(j, 0), 1e-3 * 0.8 / 4, 1e-12 * 1e-3 * 0.8 / 4);
    EXPECT_NEAR(a.contact(j, 1), -1e-3 * 0.3 / 16, 1e-12 * 1e-3 * 0.3 / 16);
    EXPECT_NEAR(a.contact(j, 2), 1e-3 * 0.05 / 64, 1e-12 * 1e-3 * 0.05 / 64);
    EXPECT_GT(a.force_order_cv[1].rms, 1e3 * a.force_order_cv[2].rms);  // lambda 2 misses the cubic term
    EXPECT_LT(a.contact_cv_rms, 1e-16);  // Measured 2.7e-19 m
  }
  for (const FitSummary& s : fit.summaries) {
    EXPECT_TRUE(s.usable) << s.what;
    EXPECT_NE(s.termination, "FAILURE") << s.what;
  }
}

TEST(SurrogateCostFunctions, CeresLevenbergMarquardtEqualsTheLinearLeastSquares) {
  // A noisy field over random 3-D points, on a basis of full rank: the paper's Marquardt (Ceres LM on the
  // residuals of surrogate_cost_functions.hpp) reaches the minimiser of sum (psi . c - t)^2 that the fit
  // computes directly (ScaledLeastSquares, docs/SURROGATE.md §3).
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const SpatialBasis basis(4, 2, 1, 0.2);
  const int n = 300;
  Eigen::MatrixX3d local(n, 3);
  for (int i = 0; i < n; ++i) local.row(i) << uniform(rng), uniform(rng), uniform(rng);
  const Eigen::MatrixXd psi = basis.evaluate(local);
  Eigen::VectorXd target(n);
  for (int i = 0; i < n; ++i)
    target[i] = std::sin(2 * local(i, 0)) * std::exp(local(i, 1)) + 0.1 * uniform(rng);
  ceres::Problem problem;
  std::vector<double> c(basis.size(), 0.0);
  for (int i = 0; i < n; ++i) {
    std::vector<double> row(psi.row(i).data(), psi.row(i).data() + 0);
    row.resize(basis.size());
    for (int k = 0; k < basis.size(); ++k) row[k] = psi(i, k);
    problem.AddResidualBlock(InducedFieldResidual::Create(row, target[i]), nullptr, c.data());
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-16;
  options.parameter_tolerance = 1e-12;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  EXPECT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();
  const ScaledLeastSquares ls(psi, SurrogateFitOptions{}.rank_threshold);
  ASSERT_EQ(ls.rank(), basis.size());
  const Eigen::VectorXd exact = ls.solve(target);
  const Eigen::VectorXd lm = Eigen::Map<Eigen::VectorXd>(c.data(), basis.size());
  EXPECT_LT((lm - exact).norm() / exact.norm(), 1e-8) << summary.BriefReport();
}

TEST(SurrogateLoadPatch, SelectsTheFacesAroundTheContactOnItsSide) {
  const core::TetMesh mesh = make_box_mesh({0, 0, 0}, {40 * kMm, 40 * kMm, 20 * kMm}, 8, 8, 4);
  const SurfaceNodes surface = surface_nodes(mesh);
  EXPECT_EQ(surface.size(), 9 * 9 * 5 - 7 * 7 * 3);  // all nodes minus the interior ones
  const int c = surface.nearest({20 * kMm, 20 * kMm, 20 * kMm});
  EXPECT_TRUE(surface.normal.row(c).isApprox(Eigen::RowVector3d(0, 0, 1), 1e-12));
  const LoadPatch p =
      load_patch(mesh, surface.position.row(c).transpose(), Eigen::Vector3d::UnitZ(), 6 * kMm);
  // On the 5 mm grid, two triangles per square: the 8 triangles of the 4 squares around the centre have their
  // centroids 2.4-4.7 mm away, the next ring's are at least 6.9 mm away.
  EXPECT_EQ(p.num_faces, 8);
  EXPECT_NEAR(p.area, 8 * 12.5 * kMm * kMm, 1e-17);  // Measured 4.1e-20 (of 1e-4 m^2)
  // The far side (the base) is never loaded, whatever the radius.
  const LoadPatch wide = load_patch(mesh, surface.position.row(c).transpose(), Eigen::Vector3d::UnitZ(), 1.0);
  EXPECT_NEAR(wide.area, 40 * 40 * kMm * kMm, 1e-15);  // Measured 2.8e-18 (of 1.6e-3 m^2)
}

TEST(SurrogateTraining, RestartingTheModelEqualsAFreshModel) {
  // EfgModel::restart keeps the set-up and the factorisation; the answer must not depend on what ran before.
  const EfgProblem problem = box_problem();
  const SurfaceNodes surface = surface_nodes(problem.mesh);
  PatchSolveOptions options;
  options.patch_radius = 6 * kMm;
  options.response_step = 2;
  options.max_workers = 1;
  const int c = surface.nearest({20 * kMm, 20 * kMm, 20 * kMm});
  const PatchLoad a{c, {0.0, 0.0, -0.05}}, b{c, {0.03, 0.0, 0.0}};
  const std::vector<SolvedLoad> both = solve_patch_loads(problem, {}, surface, {a, b}, options);
  const std::vector<SolvedLoad> fresh = solve_patch_loads(problem, {}, surface, {b}, options);
  const double scale = fresh[0].displacement.cwiseAbs().maxCoeff();
  EXPECT_GT(scale, 1e-5);
  EXPECT_LT((both[1].displacement - fresh[0].displacement).cwiseAbs().maxCoeff(), 1e-7 * scale);
}

/// A surrogate fitted to an analytic field on the box's surface nodes (no full solves: fast): for the force
/// axis j and level sigma, u(X) = (sigma / F) g_j(X) + (sigma / F)^2 h(X), where g_j is the regularised
/// point-force (Kelvin) field along j and h a smooth quadratic field.
const SurrogateData& synthetic_surrogate() {
  static const SurrogateData data = [] {
    const core::TetMesh mesh = box_problem().mesh;
    const SurfaceNodes surface = surface_nodes(mesh);
    const core::SurrogateSpec spec = box_spec();
    ContactTrainingData t;
    t.contact = surface.nearest(spec.contact_points[0]);
    t.levels = training_levels(spec);
    const Eigen::Vector3d xc = surface.position.row(t.contact).transpose();
    for (int j = 0; j < 3; ++j)
      for (double level : t.levels) {
        const double s = level / spec.max_force;
        core::PointMatrix u(surface.size(), 3);
        for (int i = 0; i < surface.size(); ++i) {
          const Eigen::Vector3d d = surface.position.row(i).transpose() - xc;
          const double rho = std::sqrt(d.squaredNorm() + spec.contact_length * spec.contact_length);
          const Eigen::Vector3d g =
              1e-3 * spec.contact_length / rho * (Eigen::Vector3d::Unit(j) + d * d[j] / (rho * rho));
          const Eigen::Vector3d h = 1e-2 * Eigen::Vector3d(d.x() * d.z(), d.y() * d.y(), d.x());
          u.row(i) = (s * g + s * s * h).transpose();
        }
        t.displacement[j].push_back(u);
      }
    SurrogateData d;
    d.case_name = "surrogate box";
    d.case_hash = "0123456789abcdef";
    d.max_force = spec.max_force;
    d.levels = t.levels;
    d.patch_radius = spec.patch_radius;
    d.response_time = "end_of_ramp";
    d.response_seconds = 1.0;
    d.surface_vertex = surface.vertex;
    d.surface_position = surface.position;
    d.contacts.push_back(fit_contact(surface, t, spec.max_force, fit_options(spec)));
    return d;
  }();
  return data;
}

// The Fig. 9 column of `tissue reproduce`: one row per force, each the answer of a direct query, a force
// beyond the trained range flagged, and a positive time per query (its size is the benchmark's business).
TEST(SurrogateQuery, ReproduceTimesOneRowPerForceWithTheQuerysAnswer) {
  const Surrogate s(synthetic_surrogate());
  const core::SurrogateSpec spec = box_spec();
  const Eigen::Vector3d point = spec.contact_points[0], direction = Eigen::Vector3d(1.0, 2.0, 2.0) / 3.0;
  const std::vector<double> forces = {0.25 * spec.max_force, spec.max_force, 1.8 * spec.max_force};
  const nlohmann::json rows = experiments::surrogate_query_timing(s, point, direction, forces, 101);
  ASSERT_EQ(rows.size(), forces.size());
  core::PointMatrix u(s.num_surface_nodes(), 3);
  for (std::size_t i = 0; i < forces.size(); ++i) {
    const SurrogateResponse direct = s.query(point, forces[i] * direction, &u);
    EXPECT_DOUBLE_EQ(rows[i].at("force_N").get<double>(), forces[i]);
    EXPECT_DOUBLE_EQ(rows[i].at("contact_displacement_mm").get<double>(), 1e3 * direct.contact_displacement.norm());
    EXPECT_GT(rows[i].at("contact_displacement_mm").get<double>(), 0.0);
    EXPECT_TRUE(rows[i].at("on_trained_contact").get<bool>());
    EXPECT_GT(rows[i].at("seconds").get<double>(), 0.0);
  }
  EXPECT_TRUE(rows[1].at("force_in_range").get<bool>());
  EXPECT_FALSE(rows[2].at("force_in_range").get<bool>()) << "2 of 3 components beyond max_force are clamped";
  EXPECT_THROW(experiments::surrogate_query_timing(s, point, direction, forces, 0), std::invalid_argument);
}

TEST(SurrogateFit, AnAnalyticFieldInTheBasisIsRecovered) {
  // The synthetic field lies in the span of force order 2, contact order 1 and a polynomial of degree 2: the
  // fit must reproduce it to round-off, and cross-validation must see that. At the contact node h vanishes,
  // so eqs. 25-27 need order 1 only while the field needs 2: each order has its own cross-validation.
  const SurrogateData& d = synthetic_surrogate();
  for (int j = 0; j < 3; ++j) {
    const AxisFit& a = d.contacts[0].axis[j];
    EXPECT_EQ(a.force_order, 1) << "axis " << j;
    EXPECT_EQ(a.field_order, 2) << "axis " << j;
    EXPECT_GT(a.field_order_cv[0].rms, 1e6 * a.field_order_cv_rms);  // order 1 misses s^2 h
    EXPECT_LT(a.training_rms, 1e-16) << "axis " << j;  // Measured 5.7e-19 m
    for (int i = 0; i < 3; ++i) {
      EXPECT_LT(a.field[i].cv_rms, 1e-16) << "axis " << j << " component " << i;  // Measured 1.8e-19 m
      EXPECT_GE(a.field[i].contact_order, 1) << "axis " << j << " component " << i;
    }
  }
  for (const FitSummary& s : d.contacts[0].summaries) {
    EXPECT_TRUE(s.usable) << s.what;
    EXPECT_NE(s.termination, "FAILURE") << s.what;
  }
}

TEST(SurrogateQuery, SuperposesTheAxesAndFlagsWhatWasNotTrained) {
  const Surrogate s(synthetic_surrogate());
  const int contact = s.data().contacts[0].contact;
  const Eigen::Vector3d x = s.data().surface_position.row(contact).transpose();
  core::PointMatrix u, ux, uy, uz;
  const Eigen::Vector3d f(0.01, -0.02, -0.03);
  const SurrogateResponse r = s.query(x, f, &u);
  EXPECT_TRUE(r.force_in_range);
  EXPECT_TRUE(r.on_trained_contact);
  EXPECT_EQ(r.contact_node, contact);
  const SurrogateResponse rx = s.query(x, {f.x(), 0, 0}, &ux), ry = s.query(x, {0, f.y(), 0}, &uy),
                          rz = s.query(x, {0, 0, f.z()}, &uz);
  // The paper's superposition of the components. Measured 1.1e-19 m
  EXPECT_LT((u - ux - uy - uz).cwiseAbs().maxCoeff(), 1e-16);
  EXPECT_TRUE(r.contact_displacement.isApprox(
      rx.contact_displacement + ry.contact_displacement + rz.contact_displacement, 1e-14));
  EXPECT_NEAR(r.max_surface_displacement, u.rowwise().norm().maxCoeff(), 1e-18);
  EXPECT_LT(r.contact_displacement.z(), 0.0);  // pressed in
  // Eqs. 25-27 at the contact node: the analytic field there is s g_j(X_c) + s^2 h(X_c) = (sigma / F) 1e-3
  // e_j.
  EXPECT_TRUE(r.contact_displacement.isApprox(1e-3 * f / s.data().max_force, 1e-10))
      << r.contact_displacement;

  // Outside the trained range: clamped to it and flagged, never extrapolated.
  core::PointMatrix clamped, edge;
  const SurrogateResponse out = s.query(x, {0, 0, -0.2}, &clamped);
  const SurrogateResponse at_edge = s.query(x, {0, 0, -0.05}, &edge);
  EXPECT_FALSE(out.force_in_range);
  EXPECT_TRUE(at_edge.force_in_range);
  EXPECT_DOUBLE_EQ(out.force.z(), -0.05);
  EXPECT_LT((clamped - edge).cwiseAbs().maxCoeff(), 1e-18);
  // Away from every trained contact: the nearest is used and the query is flagged.
  const SurrogateResponse far = s.query(x + Eigen::Vector3d(10 * kMm, 0, 0), f, &u);
  EXPECT_FALSE(far.on_trained_contact);
  EXPECT_NEAR(far.contact_distance, 10 * kMm, 1e-15);  // Measured 1.7e-18
  EXPECT_EQ(far.contact_node, contact);
}

class SurrogateFile : public ::testing::Test {
 protected:
  std::string path(const std::string& name) {
    const auto dir = std::filesystem::temp_directory_path() / "tissue_test_surrogate";
    std::filesystem::create_directories(dir);
    return (dir / name).string();
  }
  static std::string read(const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  static void write(const std::string& p, const std::string& text) {
    std::ofstream(p, std::ios::binary) << text;
  }
  static std::string error_of(const std::string& p, const std::optional<std::string>& hash = std::nullopt) {
    try {
      read_surrogate(p, hash);
    } catch (const SurrogateFileError& e) {
      return e.what();
    }
    return "no error";
  }
};

TEST_F(SurrogateFile, RoundTripGivesTheSameAnswers) {
  const std::string p = path("box.surrogate.json");
  write_surrogate(p, synthetic_surrogate());
  const SurrogateData back = read_surrogate(p, std::string("0123456789abcdef"));
  const Surrogate a(synthetic_surrogate()), b(back);
  const Eigen::Vector3d x = a.data().surface_position.row(a.data().contacts[0].contact).transpose();
  core::PointMatrix ua, ub;
  const SurrogateResponse ra = a.query(x, {0.01, 0.02, -0.04}, &ua),
                          rb = b.query(x, {0.01, 0.02, -0.04}, &ub);
  EXPECT_EQ(ua, ub);  // the JSON numbers round-trip exactly
  EXPECT_EQ(ra.contact_displacement, rb.contact_displacement);
  for (const auto& entry : std::filesystem::directory_iterator(std::filesystem::path(p).parent_path()))
    EXPECT_EQ(entry.path().filename().string().rfind(".box", 0), std::string::npos)
        << "temporary file left behind: " << entry.path();
}

TEST_F(SurrogateFile, MissingTruncatedEditedOrMismatchedFilesAreRefusedWithTheReason) {
  const std::string good = path("good.surrogate.json");
  write_surrogate(good, synthetic_surrogate());
  const std::string text = read(good);

  EXPECT_NE(error_of(path("does_not_exist.json")).find("cannot open the surrogate file"), std::string::npos);

  const std::string truncated = path("truncated.json");
  write(truncated, text.substr(0, text.size() / 2));
  EXPECT_NE(error_of(truncated).find("truncated"), std::string::npos) << error_of(truncated);

  const std::string edited = path("edited.json");
  std::string e = text;
  const std::size_t at = e.find("\"max_force\":");
  ASSERT_NE(at, std::string::npos);
  e.replace(at, 12, "\"max_force\":9");  // a digit more: a larger claimed range
  write(edited, e);
  EXPECT_NE(error_of(edited).find("checksum"), std::string::npos) << error_of(edited);

  EXPECT_NE(error_of(good, std::string("ffff")).find("the case changed"), std::string::npos);

  nlohmann::json j = nlohmann::json::parse(text);
  j["format_version"] = kSurrogateFormatVersion + 1;
  const std::string newer = path("newer.json");
  write(newer, j.dump());
  EXPECT_NE(error_of(newer).find("format version"), std::string::npos) << error_of(newer);

  j = nlohmann::json::parse(text);
  j["units"]["length"] = "mm";
  const std::string mm = path("mm.json");
  write(mm, j.dump());
  EXPECT_NE(error_of(mm).find("units"), std::string::npos) << error_of(mm);

  EXPECT_NO_THROW(read_surrogate(good, std::string("0123456789abcdef")));
}

// The shipped surrogate (results/surrogate/lung_surrogate.surrogate.json, docs/SURROGATE.md §6) loads through
// the checked reader and answers: finite, the values computed once from this file, consistent with the
// held-out comparison the file reports, and nothing at zero force (eqs. 25-28 have no constant term).
TEST_F(SurrogateFile, TheShippedLungSurrogateLoadsAndAnswers) {
  const std::string file =
      std::string(TISSUE_SOURCE_DIR) + "/results/surrogate/lung_surrogate.surrogate.json";
  SurrogateData d;
  ASSERT_NO_THROW(d = read_surrogate(file, std::nullopt)) << error_of(file);
  ASSERT_EQ(d.contacts.size(), 1u);
  ASSERT_EQ(d.surface_position.rows(), 866);
  const Surrogate s(d);
  const int node = d.contacts[0].contact;
  const Eigen::Vector3d x = d.surface_position.row(node).transpose();
  core::PointMatrix u;

  // The first held-out force of the file's report: the query against the full model's answer there.
  const nlohmann::json& holdout = d.report.at("holdout").at(0);
  const Eigen::Vector3d f(holdout.at("force_N")[0].get<double>(), holdout.at("force_N")[1].get<double>(),
                          holdout.at("force_N")[2].get<double>());
  const SurrogateResponse r = s.query(x, f, &u);
  ASSERT_TRUE(u.allFinite());
  EXPECT_TRUE(r.on_trained_contact);
  EXPECT_TRUE(r.force_in_range);
  EXPECT_EQ(r.contact_node, node);
  EXPECT_LE(std::abs(r.contact_displacement.norm() - holdout.at("contact_displacement_m").get<double>()),
            holdout.at("contact_error_m").get<double>() * (1 + 1e-9));
  // The values this file gave when the test was written (printed with 17 digits): only rounding moves them.
  const Eigen::Vector3d expected(-0.0018393711123677195, 0.00022848746724973121, -0.00054783172054346683);
  EXPECT_LT((r.contact_displacement - expected).norm(), 1e-12 * expected.norm()) << r.contact_displacement;

  // An oblique force, every axis superposed.
  const SurrogateResponse o = s.query(x, {0.1, -0.25, 0.3}, &u);
  ASSERT_TRUE(u.allFinite());
  const Eigen::Vector3d oblique(0.0027254712723213392, -0.014173960683914192, 0.016735992362864771);
  EXPECT_LT((o.contact_displacement - oblique).norm(), 1e-12 * oblique.norm()) << o.contact_displacement;
  EXPECT_NEAR(o.max_surface_displacement, 0.02210028948894702, 1e-12 * 0.0221);
  EXPECT_EQ(o.max_surface_node, node);

  const SurrogateResponse zero = s.query(x, Eigen::Vector3d::Zero(), &u);
  EXPECT_EQ(zero.contact_displacement.norm(), 0.0);
  EXPECT_EQ(u.cwiseAbs().maxCoeff(), 0.0);
}

// The command line on a surrogate file: `tissue probe` answers good lines, reports malformed ones and goes
// on, flags forces outside the trained range, replays a trace with its latency report and per-sample CSV, and
// refuses a missing, truncated or mismatched file or a malformed trace with the reason; `--help` on both.
class ProbeCommand : public SurrogateFile {
 protected:
  struct Run {
    int exit_code;
    std::string output;  // stdout + stderr
  };
  static Run run(const std::string& args, const std::string& stdin_text = "") {
    // One stdin file per test process: ctest runs the tests of this suite concurrently.
    const std::string input =
        std::filesystem::temp_directory_path() / "tissue_test_surrogate" /
        fmt::format("stdin_{}_{}.txt", ::testing::UnitTest::GetInstance()->current_test_info()->name(),
                    ::getpid());
    write(input, stdin_text);
    const std::string command = std::string(TISSUE_BINARY) + " " + args + " < " + input + " 2>&1";
    FILE* pipe = popen(command.c_str(), "r");
    EXPECT_NE(pipe, nullptr);
    std::string output;
    char buffer[4096];
    while (fgets(buffer, sizeof buffer, pipe)) output += buffer;
    const int status = pclose(pipe);
    return {WEXITSTATUS(status), output};
  }
  std::string good_file() {
    const std::string p = path("probe.surrogate.json");
    write_surrogate(p, synthetic_surrogate());
    return p;
  }
  /// The synthetic surrogate's contact node [mm], as a probe line's first three numbers.
  static std::string contact_mm() {
    const SurrogateData& d = synthetic_surrogate();
    const Eigen::Vector3d x = d.surface_position.row(d.contacts[0].contact).transpose() / kMm;
    return fmt::format("{:.6f} {:.6f} {:.6f}", x.x(), x.y(), x.z());
  }
  static int count(const std::string& text, const std::string& what) {
    int n = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  }
};

TEST_F(ProbeCommand, HelpDescribesBothCommands) {
  const Run probe = run("probe --help"), fit = run("fit --help");
  EXPECT_EQ(probe.exit_code, 0) << probe.output;
  EXPECT_NE(probe.output.find("--trace"), std::string::npos) << probe.output;
  EXPECT_NE(probe.output.find("--rate"), std::string::npos) << probe.output;
  EXPECT_EQ(fit.exit_code, 0) << fit.output;
  EXPECT_NE(fit.output.find("--out"), std::string::npos) << fit.output;
  const Run no_out = run("fit " + std::string(TISSUE_TEST_CONFIG_DIR) + "/lung_surrogate.json");
  EXPECT_NE(no_out.exit_code, 0);
  EXPECT_NE(no_out.output.find("--out"), std::string::npos) << no_out.output;
}

TEST_F(ProbeCommand, InteractiveAnswersReportsMalformedLinesAndFlagsUntrainedForces) {
  const std::string file = good_file();
  const std::string lines = "# a comment\n" + contact_mm() + " 0 0 -0.03\n" + "1 2 three 0 0 0\n" +
                            contact_mm() + " 0 0 -0.2\n" + "1 2 3\n" + contact_mm() + ", 0.01, 0, 0\n";
  const Run r = run("probe " + file, lines);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(count(r.output, "contact node "), 3) << r.output;  // the three good lines, the loop went on
  EXPECT_NE(r.output.find("error: line 3: expected six numbers"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("error: line 5: expected six numbers"), std::string::npos) << r.output;
  EXPECT_EQ(count(r.output, "force outside the trained range"), 1) << r.output;
  EXPECT_NE(r.output.find("2 malformed line(s) skipped"), std::string::npos) << r.output;
  // The first answer: eqs. 25-27 at the contact node give (sigma / F) 1 mm along the force (the analytic
  // field of synthetic_surrogate()), so -0.03 N of 0.05 N is -0.6 mm along z.
  EXPECT_NE(r.output.find(", -0.60000) mm, |u| = 0.60000 mm"), std::string::npos) << r.output;
}

TEST_F(ProbeCommand, ReplayReportsLatencyAndWritesOneRowPerSample) {
  const std::string file = good_file(), trace = path("trace.csv"), out = path("trace.probe.csv");
  std::string rows = "t,x,y,z,fx,fy,fz\n";
  const int n = 50;
  for (int i = 0; i < n; ++i) {
    const double f = i == n - 1 ? -0.08 : -0.04 * i / n;  // the last one beyond the trained 0.05 N
    rows += fmt::format("{},{},0,0,{}\n", 1e-3 * i, contact_mm(), f);
  }
  std::replace(rows.begin(), rows.end(), ' ', ',');
  write(trace, rows);
  std::filesystem::remove(out);
  const Run r = run("probe " + file + " --trace " + trace + " --rate 1000 --out " + out);
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find(fmt::format("replayed {} samples at 1000 Hz", n)), std::string::npos) << r.output;
  for (const char* field : {"latency p50", "p99", "max", "missed deadlines:"})
    EXPECT_NE(r.output.find(field), std::string::npos) << field << "\n" << r.output;
  EXPECT_NE(r.output.find("flagged: 1 sample(s) with a force outside"), std::string::npos) << r.output;
  const std::string csv = read(out);
  EXPECT_EQ(count(csv, "\n"), n + 1) << csv.substr(0, 400);  // header + one row per sample
  EXPECT_EQ(csv.rfind("sample,t_s,x_mm", 0), 0u);
}

TEST_F(ProbeCommand, BadFilesAndTracesAreRefusedWithTheReason) {
  const std::string file = good_file();
  const Run missing = run("probe " + path("nowhere.surrogate.json"), "");
  EXPECT_NE(missing.exit_code, 0);
  EXPECT_NE(missing.output.find("cannot open the surrogate file"), std::string::npos) << missing.output;

  const std::string truncated = path("probe_truncated.json");
  const std::string text = read(file);
  write(truncated, text.substr(0, text.size() / 3));
  const Run cut = run("probe " + truncated, "");
  EXPECT_NE(cut.exit_code, 0);
  EXPECT_NE(cut.output.find("truncated"), std::string::npos) << cut.output;

  // Fitted on the box, checked against the shipped lung case: another case's hash.
  const Run other =
      run("probe " + file + " --case " + std::string(TISSUE_TEST_CONFIG_DIR) + "/lung_surrogate.json", "");
  EXPECT_NE(other.exit_code, 0);
  EXPECT_NE(other.output.find("the case changed since the fit"), std::string::npos) << other.output;

  const std::string bad_trace = path("bad_trace.csv");
  write(bad_trace, "t,x,y,z,fx,fy,fz\n0,1,2,3,0,0,0\n0.001,1,2,3,0,zero,0\n");
  const Run malformed = run("probe " + file + " --trace " + bad_trace, "");
  EXPECT_NE(malformed.exit_code, 0);
  EXPECT_NE(malformed.output.find("bad_trace.csv:3: expected seven numbers"), std::string::npos)
      << malformed.output;
  const Run no_trace = run("probe " + file + " --trace " + path("no_trace.csv"), "");
  EXPECT_NE(no_trace.exit_code, 0);
  EXPECT_NE(no_trace.output.find("cannot open the trace"), std::string::npos) << no_trace.output;
  const Run bad_rate = run("probe " + file + " --trace " + bad_trace + " --rate 0", "");
  EXPECT_NE(bad_rate.exit_code, 0);
  EXPECT_NE(bad_rate.output.find("--rate"), std::string::npos) << bad_rate.output;
}

}  // namespace
}  // namespace meshless
