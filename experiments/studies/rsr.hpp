#pragma once
// Rank-sum-ratio (RSR) evaluation of the paper's §5.6 (Tian's method): ranks (Table 3), RSR (Table 4,
// eq. 36), the RSR distribution with probits (Table 5), the regression RSR = a + b·Probit (eq. 37) and the
// grading (Table 6). Pure computation; `tissue rsr` (rsr_command.cpp) reads the scores and prints the tables.
//
// Conventions (docs/EXPERIMENTS.md §rsr):
// - every indicator is ranked over the n objects from 1 (worst) to n (best); tied scores share their average
//   rank; an indicator marked lower-is-better is ranked in reverse;
// - RSR_i = Σ_j R_ij / (m·n) (eq. 36);
// - the distribution groups equal RSR values; group g covers ranks Σf_{g-1}+1 … Σf_g, its mean rank is
//   R̄_g and its percentage p_g = R̄_g / n, except the last group, whose p = 1 − 1/(4n);
// - Probit_g = 5 + Φ⁻¹(p_g) (Φ⁻¹ from Boost.Math);
// - the regression is ordinary least squares of RSR_g on Probit_g over the groups (one point per distinct
//   RSR value);
// - three grades (Tian's table): poor for Probit < 4, good for 4 ≤ Probit < 6, excellent for Probit ≥ 6; the
//   RSR thresholds are the regression's values at Probit 4 and 6, and each object is graded by its fitted RSR.
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace experiments {

/// Scores of n objects (rows) on m indicators (columns).
struct ScoreTable {
  std::vector<std::string> objects;     ///< n names
  std::vector<std::string> indicators;  ///< m names
  Eigen::MatrixXd scores;               ///< n by m
  std::vector<bool> lower_is_better;    ///< m flags; false = a benefit ("high-quality") indicator

  /// Checks the shapes, finiteness, n >= 2 and m >= 1; on failure says what is wrong in `why`.
  bool IsValid(std::string* why) const;
};

/// Read a score table from CSV: a header `name,I1,...,Im`, then one row per object (its name, then m
/// numbers). Blank lines are skipped. Throws std::invalid_argument naming the file, the line and the column.
ScoreTable read_score_table(const std::string& path);

/// One group of equal RSR values in the distribution table (Table 5).
struct RsrGroup {
  double rsr = 0.0;
  int frequency = 0;           ///< f
  int cumulative = 0;          ///< Σf
  int first_rank = 0;          ///< R range: first_rank … cumulative
  double mean_rank = 0.0;      ///< R̄
  double percent = 0.0;        ///< 100·R̄/n, or 100·(1 − 1/(4n)) for the last group
  bool corrected = false;      ///< true for the last group
  double probit = 0.0;         ///< 5 + Φ⁻¹(percent/100)
};

struct RsrGrade {
  std::string name;            ///< "poor", "good", "excellent"
  double probit_from = 0.0;    ///< lower bound (-inf for the lowest grade)
  double rsr_from = 0.0;       ///< a + b·probit_from (-inf for the lowest grade)
  std::vector<std::string> objects;
};

struct RsrResult {
  ScoreTable table;
  Eigen::MatrixXd ranks;             ///< n by m (Table 3)
  std::vector<double> rsr;           ///< per object (Table 4, eq. 36)
  std::vector<RsrGroup> groups;      ///< ascending RSR (Table 5)
  std::vector<int> group_of_object;  ///< index into groups
  double intercept = 0.0;            ///< a in RSR = a + b·Probit (eq. 37)
  double slope = 0.0;                ///< b
  double r_squared = 0.0;            ///< of the regression over the groups
  std::vector<double> fitted_rsr;    ///< a + b·Probit per object
  std::vector<RsrGrade> grades;      ///< poor, good, excellent (Table 6)
  std::vector<int> grade_of_object;  ///< index into grades
};

/// Φ⁻¹(p) of the standard normal distribution, p in (0, 1) (Boost.Math quantile).
double normal_quantile(double p);

/// Average ranks of `values` in ascending order (1 = smallest); ties share the mean of their ranks.
std::vector<double> average_ranks(const std::vector<double>& values);

/// The whole evaluation. Throws std::invalid_argument when the table is invalid or when every object has
/// the same RSR (one group: no regression is possible).
RsrResult evaluate_rsr(const ScoreTable& table);

/// Tables 3–6 and the regression as Markdown (RSR, R̄ and Probit with 4 decimals, percentages with 1).
std::string rsr_markdown(const RsrResult& result);
/// Every figure at full precision.
nlohmann::json rsr_json(const RsrResult& result);

}  // namespace experiments
