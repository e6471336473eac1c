// Another program's sample displacements (`tissue compare --external NAME=FILE.csv`): scored by the comparator's
// own code against a reference with known answers, and every malformed or mismatched file refused with its line and
// what was expected. The reader and the scoring need no solve; the command's refusals need at most the geometry
// (seconds): they must come before any solve.
#include <gtest/gtest.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "experiments/comparator/compare.hpp"
#include "experiments/models/external/external_result.hpp"
#include "experiments/models/model_registry.hpp"
#include "experiments/models/model_result.hpp"
#include "tests/tissue_process.hpp"

namespace fs = std::filesystem;
using nlohmann::json;
using experiments::ExternalResultError;

namespace {

const char* kHeader = "sample,x_mm,y_mm,z_mm,ux_mm,uy_mm,uz_mm,magnitude_mm";

fs::path temp_dir(const std::string& tag) {
  const fs::path d = fs::temp_directory_path() / ("tissue_external_" + tag + "_" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

/// The three samples of the synthetic case [mm]: 5, 12 (on the load-patch edge) and 30 mm from the load centre.
Eigen::MatrixXd points_mm() {
  Eigen::MatrixXd x(3, 3);
  x << 5, 0, 0, 12, 0, 0, 30, 0, 0;
  return x;
}

/// The reference's sample displacements [mm]; peak 4 mm.
Eigen::MatrixXd reference_mm() {
  Eigen::MatrixXd u(3, 3);
  u << 4, 0, 0, 2, 0, 0, 1, 0, 0;
  return u;
}

/// A CSV row in the samples.csv format, magnitude computed.
std::string row(int sample, const Eigen::Vector3d& x_mm, const Eigen::Vector3d& u_mm) {
  std::ostringstream s;
  s.precision(17);
  s << sample << "," << x_mm(0) << "," << x_mm(1) << "," << x_mm(2) << "," << u_mm(0) << "," << u_mm(1) << ","
    << u_mm(2) << "," << u_mm.norm() << "\n";
  return s.str();
}

std::string csv_of(const Eigen::MatrixXd& x_mm, const Eigen::MatrixXd& u_mm) {
  std::string csv = std::string(kHeader) + "\n";
  for (Eigen::Index i = 0; i < x_mm.rows(); ++i)
    csv += row(static_cast<int>(i), x_mm.row(i).transpose(), u_mm.row(i).transpose());
  return csv;
}

class ExternalResult : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = temp_dir(::testing::UnitTest::GetInstance()->current_test_info()->name()); }
  void TearDown() override { fs::remove_all(dir_); }

  std::string write(const std::string& text, const std::string& name = "other.csv") const {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p.string();
  }

  /// Read `text` as an external file of the 3-sample case and match it to the case's samples.
  experiments::ModelResult score(const std::string& text) const {
    const std::string file = write(text);
    return experiments::external_model_result(experiments::read_external_samples(file, 3), "other",
                                              points_mm() * 1e-3);
  }

  /// The message of the refusal of `text`; fails the test when it is accepted.
  std::string refusal(const std::string& text) const {
    try {
      score(text);
    } catch (const ExternalResultError& e) {
      return e.what();
    }
    ADD_FAILURE() << "accepted:\n" << text;
    return {};
  }

  fs::path dir_;
};

#define EXPECT_HAS(haystack, needle) EXPECT_NE((haystack).find(needle), std::string::npos) << (haystack)

/// The synthetic comparison of test_compare (three samples, sample 1 on the load-patch edge) with `external` added.
experiments::Comparison comparison_with(experiments::ModelResult external) {
  experiments::Comparison c;
  c.case_name = "synthetic";
  c.config = "synthetic.json";
  c.sample_points = points_mm() * 1e-3;
  c.reference.sample_displacements = reference_mm() * 1e-3;
  c.reference.total_seconds = 10.0;
  experiments::ModelResult enrichment, visibility;
  enrichment.sample_displacements = c.reference.sample_displacements * 0.9;
  visibility.sample_displacements = c.reference.sample_displacements * 0.5;
  enrichment.role = "proposed";
  visibility.role = "baseline";
  c.models = {{"enrichment", enrichment}, {"visibility", visibility}, {"other", std::move(external)}};
  c.rules.patch_edge_distance = 0.001;
  c.rules.cut_distance = 0.010;
  c.diagnostics = experiments::diagnose_samples(c.sample_points, Eigen::Vector3d::Zero(), 0.012, std::nullopt, c.rules);
  c.error_bar.known = true;
  c.error_bar.rms_mm = 0.05;
  c.error_bar.relative = 0.02;
  c.error_bar.method = "synthetic";
  return c;
}

TEST_F(ExternalResult, TheReferencesOwnSamplesScoreZeroExactly) {
  const experiments::ModelResult r = score(csv_of(points_mm(), reference_mm()));
  EXPECT_EQ(r.model, "other");
  EXPECT_EQ(r.role, "external");
  EXPECT_EQ(r.details["largest_position_offset_mm"].get<double>(), 0.0);
  const json s = experiments::comparison_summary(comparison_with(r));
  const json& m = s["models"]["other"];
  EXPECT_EQ(m["rmse_mm"].get<double>(), 0.0);
  EXPECT_EQ(m["rmse_unflagged_mm"].get<double>(), 0.0);
  EXPECT_EQ(m["max_sample_error_mm"].get<double>(), 0.0);
}

TEST_F(ExternalResult, AKnownPerturbationScoresItsRmseWithTheSameFlagsAndErrorBar) {
  Eigen::MatrixXd u = reference_mm();
  u(0, 2) += 0.3;  // sample 0 off by 0.3 mm
  u(1, 1) += 0.4;  // sample 1, flagged on the load-patch edge, off by 0.4 mm
  const json s = experiments::comparison_summary(comparison_with(score(csv_of(points_mm(), u))));
  EXPECT_EQ(s["flagged_samples"], json::array({1}));
  const json& m = s["models"]["other"];
  EXPECT_NEAR(m["rmse_mm"].get<double>(), std::sqrt((0.09 + 0.16) / 3.0), 1e-12);
  EXPECT_NEAR(m["rmse_relative_to_peak"].get<double>(), std::sqrt((0.09 + 0.16) / 3.0) / 4.0, 1e-12);
  EXPECT_NEAR(m["rmse_unflagged_mm"].get<double>(), std::sqrt(0.09 / 2.0), 1e-12);
  EXPECT_EQ(m["n_unflagged"], 2);
  EXPECT_NEAR(m["max_sample_error_mm"].get<double>(), 0.4, 1e-12);
  EXPECT_EQ(m["reference_error_bar_mm"].get<double>(), 0.05);
  EXPECT_EQ(m["role"], "external");
  EXPECT_TRUE(m["timings"].is_null());
  EXPECT_HAS(m["details"]["source"].get<std::string>(), "other.csv");
  // The Table 1 difference stays the two meshless variants'.
  EXPECT_NEAR(s["difference_mm"].get<double>(),
              s["models"]["enrichment"]["rmse_mm"].get<double>() - s["models"]["visibility"]["rmse_mm"].get<double>(),
              1e-15);
}

TEST_F(ExternalResult, AppearsInTheComparisonsSamplesCsvAndTable) {
  Eigen::MatrixXd u = reference_mm();
  u(0, 2) += 0.3;
  const experiments::Comparison c = comparison_with(score(csv_of(points_mm(), u)));
  const std::string csv = experiments::comparison_samples_csv(c);
  EXPECT_HAS(csv, "\n0,other,5.000000,0.000000,0.000000,4,0,0.3,4.01123422,0.3,7.000000,,0,0,0\n");
  const std::string md = experiments::comparison_table_md(c, experiments::comparison_summary(c));
  EXPECT_HAS(md, "| other | 0.1732 | 4.3 % | 0.2121 | 5.3 % | 0.0500 | 0.3000 | – |");
  EXPECT_HAS(md, "other: external, another program's samples read from");
}

TEST_F(ExternalResult, HasNoCutEffectAndDoesNotNeedAnUncutSolve) {
  experiments::Comparison c = comparison_with(score(csv_of(points_mm(), reference_mm())));
  c.has_cut = true;
  c.uncut_samples = {{"fem", c.reference.sample_displacements * 0.5},
                     {"enrichment", c.models[0].second.sample_displacements * 0.5},
                     {"visibility", c.models[1].second.sample_displacements * 0.5}};
  const json s = experiments::comparison_summary(c);
  EXPECT_TRUE(s["cut_effect"]["models"].contains("enrichment"));
  EXPECT_FALSE(s["cut_effect"]["models"].contains("other"));
}

TEST_F(ExternalResult, ASamplesCsvWrittenByASolveIsReadAsIs) {
  experiments::ModelResult solved;
  solved.sample_points = points_mm() * 1e-3;
  solved.sample_displacements = reference_mm() * 1e-3;
  solved.sample_displacements(2, 1) = 1.234567891234e-4;
  solved.sample_cut_distance = {0.02, 0.01, 0.0};
  solved.sample_lip = {0, 1, -1};
  const std::string file = (dir_ / "samples.csv").string();
  experiments::write_samples_csv(file, solved);
  const experiments::ModelResult r = experiments::external_model_result(
      experiments::read_external_samples(file, 3), "fem_again", points_mm() * 1e-3);
  // samples.csv keeps 9 significant digits.
  EXPECT_LT((r.sample_displacements - solved.sample_displacements).cwiseAbs().maxCoeff(), 1e-9 * 4e-3);
}

TEST_F(ExternalResult, AcceptsTheCutColumnsEmptyOrAbsentAndWindowsLineEnds) {
  const std::string header = std::string(kHeader) + ",cut_distance_mm,lip\r\n";
  const std::string rows = "0,5,0,0,4,0,0,4,,\r\n1,12,0,0,2,0,0,2,3.5,1\r\n2,30,0,0,1,0,0,1,,0\r\n\r\n";
  EXPECT_EQ(score(header + rows).sample_displacements(1, 0), 2e-3);
  EXPECT_EQ(score(csv_of(points_mm(), reference_mm())).sample_displacements.rows(), 3);
  // Rows in any order: matched by index.
  EXPECT_EQ(score(std::string(kHeader) + "\n2,30,0,0,1,0,0,1\n0,5,0,0,4,0,0,4\n1,12,0,0,2,0,0,2\n")
                .sample_displacements(0, 0),
            4e-3);
}

TEST_F(ExternalResult, RefusesAMissingFile) {
  try {
    experiments::read_external_samples((dir_ / "nowhere.csv").string(), 3);
    FAIL() << "accepted a missing file";
  } catch (const ExternalResultError& e) {
    EXPECT_HAS(std::string(e.what()), "nowhere.csv: expected a CSV of sample displacements");
    EXPECT_HAS(std::string(e.what()), "the file does not exist");
  }
}

TEST_F(ExternalResult, RefusesAnEmptyFileAndAWrongHeader) {
  EXPECT_HAS(refusal(""), "other.csv: line 1: expected the header sample,x_mm,y_mm,z_mm,ux_mm,uy_mm,uz_mm,magnitude_mm");
  const std::string wrong = refusal("sample,x_mm,y_mm,z_mm,u_x,uy_mm,uz_mm,magnitude_mm\n0,5,0,0,4,0,0,4\n");
  EXPECT_HAS(wrong, "other.csv: line 1: column 5 is \"u_x\", expected \"ux_mm\": the header must be sample,x_mm");
  EXPECT_HAS(refusal("sample,x_mm,y_mm,z_mm\n"), "line 1: 4 columns, expected at least 8");
  EXPECT_HAS(refusal(std::string(kHeader) + ",cut_distance_mm,lip,extra\n"),
             "line 1: column 11 \"extra\" is not a column of samples.csv");
}

TEST_F(ExternalResult, RefusesColumnsInMetres) {
  const std::string m = refusal("sample,x_m,y_m,z_m,ux_m,uy_m,uz_m,magnitude_m\n0,0.005,0,0,0.004,0,0,0.004\n");
  EXPECT_HAS(m, "other.csv: line 1: column 2 is \"x_m\", but the file must be in millimetres: expected \"x_mm\"");
  // Metres under a header in mm: the positions give it away.
  const std::string p = refusal(csv_of(points_mm() * 1e-3, reference_mm() * 1e-3));
  EXPECT_HAS(p, "other.csv: line 2: sample 0 is at (0.005000, 0.000000, 0.000000) mm, but the case's sample 0 is at "
                "(5.000000, 0.000000, 0.000000) mm, 4.995000 mm away; expected within 0.001 mm");
  EXPECT_HAS(p, "the file's positions look like metres, but samples.csv is in mm");
}

TEST_F(ExternalResult, RefusesAWrongSampleCount) {
  Eigen::MatrixXd x4(4, 3), u4(4, 3);
  x4 << points_mm(), Eigen::RowVector3d(40, 0, 0);
  u4 << reference_mm(), Eigen::RowVector3d(0.5, 0, 0);
  EXPECT_HAS(refusal(csv_of(x4, u4)), "other.csv: line 5: a row beyond the case's 3 samples: the file holds 4 sample "
                                      "rows, expected 3, one per sample of the case (samples 0 to 2)");
  EXPECT_HAS(refusal(csv_of(points_mm().topRows(2), reference_mm().topRows(2))),
             "other.csv: 2 sample rows (lines 2 to 3), expected 3, one per sample of the case (samples 0 to 2): "
             "missing sample 2");
  EXPECT_HAS(refusal(std::string(kHeader) + "\n"), "other.csv: no sample rows after the header on line 1; expected 3");
}

TEST_F(ExternalResult, RefusesAPositionThatIsNotTheCasesSample) {
  Eigen::MatrixXd x = points_mm();
  x(1, 1) = 0.5;
  EXPECT_HAS(refusal(csv_of(x, reference_mm())),
             "other.csv: line 3: sample 1 is at (12.000000, 0.500000, 0.000000) mm, but the case's sample 1 is at "
             "(12.000000, 0.000000, 0.000000) mm, 0.500000 mm away; expected within 0.001 mm; the rows must be this "
             "case's samples, by index");
  // Within the tolerance (1 µm, e.g. another program's rounding) it is accepted, and the offset reported.
  x(1, 1) = 0.0009;
  EXPECT_NEAR(score(csv_of(x, reference_mm())).details["largest_position_offset_mm"].get<double>(), 0.0009, 1e-15);
  // Two samples' indices swapped.
  const std::string swapped = std::string(kHeader) + "\n0,5,0,0,4,0,0,4\n2,12,0,0,2,0,0,2\n1,30,0,0,1,0,0,1\n";
  EXPECT_HAS(refusal(swapped), "line 4: sample 1 is at (30.000000, 0.000000, 0.000000) mm");
  EXPECT_HAS(refusal(swapped), "that is the position of the case's sample 2");
}

TEST_F(ExternalResult, RefusesNonFiniteAndNonNumericValues) {
  const std::string h = std::string(kHeader) + "\n0,5,0,0,4,0,0,4\n";
  EXPECT_HAS(refusal(h + "1,12,0,0,2,nan,0,2\n2,30,0,0,1,0,0,1\n"),
             "other.csv: line 3: column uy_mm: expected a finite number, got nan");
  EXPECT_HAS(refusal(h + "1,12,0,0,2,0,0,2\n2,inf,0,0,1,0,0,1\n"),
             "other.csv: line 4: column x_mm: expected a finite number, got inf");
  EXPECT_HAS(refusal(h + "1,12,0,0,2,0,0,2\n2,30,0,0,1 mm,0,0,1\n"),
             "other.csv: line 4: column ux_mm: expected a number, got \"1 mm\"");
  EXPECT_HAS(refusal(h + "1,12,0,,2,0,0,2\n"), "other.csv: line 3: column z_mm: expected a number, got an empty field");
  EXPECT_HAS(refusal(h + "one,12,0,0,2,0,0,2\n"),
             "other.csv: line 3: column sample: expected a sample index (an integer >= 0), got \"one\"");
  EXPECT_HAS(refusal(h + "1,12,0,0,2,0,0\n"), "other.csv: line 3: 7 fields, expected 8 (one per column of the header)");
  EXPECT_HAS(refusal(h + "1,12,0,0,2,0,0,2.5\n"),
             "other.csv: line 3: column magnitude_mm: expected ‖(ux, uy, uz)‖ = 2 mm (eq. 33; within 0.001 of it), got "
             "2.5");
  EXPECT_HAS(refusal(std::string(kHeader) + ",cut_distance_mm,lip\n0,5,0,0,4,0,0,4,,2\n"),
             "other.csv: line 2: column lip: expected empty, -1, 0 or 1, got 2");
}

TEST_F(ExternalResult, RefusesADuplicateMissingOrUnknownSampleIndex) {
  EXPECT_HAS(refusal(std::string(kHeader) + "\n0,5,0,0,4,0,0,4\n1,12,0,0,2,0,0,2\n1,12,0,0,2,0,0,2\n"),
             "other.csv: line 4: sample 1 again (first on line 3); expected each sample index once");
  EXPECT_HAS(refusal(std::string(kHeader) + "\n0,5,0,0,4,0,0,4\n2,30,0,0,1,0,0,1\n"),
             "other.csv: 2 sample rows (lines 2 to 3), expected 3, one per sample of the case (samples 0 to 2): "
             "missing sample 1");
  // 1-based indices.
  EXPECT_HAS(refusal(std::string(kHeader) + "\n1,5,0,0,4,0,0,4\n2,12,0,0,2,0,0,2\n3,30,0,0,1,0,0,1\n"),
             "other.csv: line 4: sample 3 is not a sample of the case, which has 3 (samples 0 to 2; indices are "
             "0-based");
  EXPECT_HAS(refusal(std::string(kHeader) + "\n-1,5,0,0,4,0,0,4\n"),
             "line 2: column sample: expected a sample index (an integer >= 0), got -1");
}

TEST_F(ExternalResult, RefusesABadName) {
  const auto parse_refusal = [](const std::string& argument) -> std::string {
    try {
      experiments::parse_external_spec(argument);
    } catch (const ExternalResultError& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_HAS(parse_refusal("=calculix.csv"), "--external =calculix.csv: expected NAME=FILE with a non-empty NAME");
  EXPECT_HAS(parse_refusal("calculix.csv"), "--external calculix.csv: expected NAME=FILE");
  EXPECT_HAS(parse_refusal("ccx="), "--external ccx=: expected NAME=FILE with a non-empty FILE");
  EXPECT_HAS(parse_refusal("my model=a.csv"), "NAME \"my model\" holds ' ': expected letters, digits, '_', '-' or '.'");
  const auto spec = experiments::parse_external_spec("ccx-2.20=out/a=b.csv");
  EXPECT_EQ(spec.name, "ccx-2.20");
  EXPECT_EQ(spec.file, "out/a=b.csv");

  const auto names_refusal = [](const std::vector<experiments::ExternalSpec>& specs) -> std::string {
    try {
      experiments::check_external_names(specs, experiments::registered_model_names());
    } catch (const ExternalResultError& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_HAS(names_refusal({{"Visibility", "v.csv"}}),
             "--external Visibility=v.csv: NAME \"Visibility\" is a built-in model's name; expected another name (the "
             "built-in models are fem, enrichment, visibility, paper, lrpim, zero)");
  EXPECT_HAS(names_refusal({{"ccx", "a.csv"}, {"abaqus", "b.csv"}, {"ccx", "c.csv"}}),
             "--external ccx=c.csv: NAME \"ccx\" is given twice (also as --external ccx=a.csv)");
  EXPECT_EQ(names_refusal({{"ccx", "a.csv"}, {"abaqus", "a.csv"}}), "accepted");
}

// The command refuses a bad file before any solve and leaves nothing behind: the count right after reading the case,
// the positions right after the geometry (seconds on the CI lung).
using CommandOutcome = tissue_test::TissueRun;
using tissue_test::run_tissue;

TEST_F(ExternalResult, CompareRefusesABadFileBeforeAnySolve) {
  const std::string config = std::string(TISSUE_TEST_CONFIG_DIR) + "/ci/lung_small_ci.json";  // 10 samples
  const fs::path out = dir_ / "out";
  const std::string base = "compare " + config + " --out " + out.string() + " --no-plot";

  const CommandOutcome count = run_tissue(base + " --external ccx=" + write(csv_of(points_mm(), reference_mm())));
  EXPECT_EQ(count.exit_code, 2) << count.output;
  EXPECT_HAS(count.output, "other.csv: 3 sample rows (lines 2 to 4), expected 10, one per sample of the case");
  EXPECT_EQ(count.output.find("Gmsh"), std::string::npos) << "refused before the geometry:\n" << count.output;

  Eigen::MatrixXd x = Eigen::MatrixXd::Zero(10, 3), u = Eigen::MatrixXd::Zero(10, 3);
  x.col(0).setLinSpaced(10, 1.0, 10.0);
  const CommandOutcome position = run_tissue(base + " --external ccx=" + write(csv_of(x, u), "ten.csv"));
  EXPECT_EQ(position.exit_code, 2) << position.output;
  EXPECT_HAS(position.output, "ten.csv: line 2: sample 0 is at (1.000000, 0.000000, 0.000000) mm, but the case's "
                              "sample 0 is at (");
  EXPECT_EQ(position.output.find("FEM reference"), std::string::npos) << "refused before the FEM solve:\n"
                                                                      << position.output;

  const CommandOutcome name = run_tissue(base + " --external fem=" + write(csv_of(x, u), "ten.csv"));
  EXPECT_EQ(name.exit_code, 2) << name.output;
  EXPECT_HAS(name.output, "NAME \"fem\" is a built-in model's name");
  EXPECT_FALSE(fs::exists(out)) << "a refused compare must leave nothing behind";
}

// The whole loop on a tiny case (40 mm FEM mesh, 24 mm cloud, one step; about 15 s): `tissue solve fem` writes
// samples.csv, and compare scores that file, as is and shifted by 0.1 mm, beside its own models.
TEST_F(ExternalResult, CompareScoresASolvesSamplesCsvBesideItsOwnModels) {
  std::ifstream in(std::string(TISSUE_TEST_CONFIG_DIR) + "/ci/lung_small_ci.json");
  json tiny = json::parse(in);
  tiny["name"] = "tiny";
  tiny["geometry"]["mesh_size"] = 40.0;
  tiny["meshless"]["node_spacing"] = 24.0;
  tiny["time"]["steps"] = 1;
  const std::string config = write(tiny.dump(2), "tiny.json");
  const CommandOutcome solve = run_tissue("solve fem " + config + " --out " + (dir_ / "fem").string());
  ASSERT_EQ(solve.exit_code, 0) << solve.output;

  std::ifstream samples(dir_ / "fem" / "samples.csv");
  std::string shifted, line;
  for (int n = 0; std::getline(samples, line); ++n) {
    if (n > 0) {  // ux + 0.1 mm, and the magnitude to match
      std::vector<std::string> f;
      std::stringstream fields(line);
      for (std::string field; std::getline(fields, field, ',');) f.push_back(field);
      Eigen::Vector3d u(std::stod(f[4]) + 0.1, std::stod(f[5]), std::stod(f[6]));
      std::ostringstream s;
      s.precision(17);
      s << f[0] << "," << f[1] << "," << f[2] << "," << f[3] << "," << u(0) << "," << u(1) << "," << u(2) << ","
        << u.norm();
      line = s.str();
    } else {
      line = kHeader;
    }
    shifted += line + "\n";
  }
  const std::string shifted_file = write(shifted, "shifted.csv");
  const fs::path out = dir_ / "compare";
  const CommandOutcome compare =
      run_tissue("compare " + config + " --out " + out.string() + " --no-plot --external fem_again=" +
                 (dir_ / "fem" / "samples.csv").string() + " --external shifted=" + shifted_file);
  ASSERT_EQ(compare.exit_code, 0) << compare.output;
  std::ifstream summary_file(out / "summary.json");
  const json s = json::parse(summary_file);
  // The same FEM solve, to the 9 significant digits of samples.csv.
  EXPECT_LT(s["models"]["fem_again"]["rmse_mm"].get<double>(), 1e-7);
  EXPECT_NEAR(s["models"]["shifted"]["rmse_mm"].get<double>(), 0.1, 1e-6);
  EXPECT_EQ(s["models"]["shifted"]["role"], "external");
  EXPECT_TRUE(s["models"].contains("enrichment"));
  std::ifstream table(out / "table.md");
  const std::string md((std::istreambuf_iterator<char>(table)), std::istreambuf_iterator<char>());
  EXPECT_HAS(md, "| shifted | 0.1000 |");
  std::ifstream csv(out / "samples.csv");
  const std::string rows((std::istreambuf_iterator<char>(csv)), std::istreambuf_iterator<char>());
  EXPECT_HAS(rows, "\n9,shifted,");
  EXPECT_FALSE(fs::exists(out / "shifted")) << "an external result has no timings.json";
}

}  // namespace
