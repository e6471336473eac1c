#include "experiments/studies/rsr.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <boost/math/distributions/normal.hpp>
#include <cmath>
#include <fstream>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace experiments {
namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

/// Split a CSV line at commas. The score file holds names and numbers only, so quoted fields are refused
/// with a message instead of being half-understood.
std::vector<std::string> split_fields(const std::string& line, const std::string& where) {
  if (line.find('"') != std::string::npos)
    throw std::invalid_argument(where + ": quoted fields are not supported; write names without commas or quotes");
  std::vector<std::string> fields;
  std::stringstream ss(line);
  std::string field;
  while (std::getline(ss, field, ',')) fields.push_back(trim(field));
  if (!line.empty() && line.back() == ',') fields.push_back("");
  return fields;
}

}  // namespace

bool ScoreTable::IsValid(std::string* why) const {
  const auto fail = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  const auto n = static_cast<Eigen::Index>(objects.size()), m = static_cast<Eigen::Index>(indicators.size());
  if (n < 2) return fail(fmt::format("need at least 2 objects to rank, got {}", n));
  if (m < 1) return fail("need at least 1 indicator");
  if (scores.rows() != n || scores.cols() != m)
    return fail(fmt::format("scores are {} by {}, expected {} by {}", scores.rows(), scores.cols(), n, m));
  if (lower_is_better.size() != indicators.size())
    return fail(fmt::format("{} lower-is-better flags for {} indicators", lower_is_better.size(), m));
  if (!scores.allFinite()) return fail("scores must be finite numbers");
  return true;
}

ScoreTable read_score_table(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument(path + ": cannot open the score file");
  ScoreTable t;
  std::string line;
  int line_no = 0;
  std::vector<std::vector<double>> rows;
  while (std::getline(in, line)) {
    ++line_no;
    if (trim(line).empty()) continue;
    const std::string where = fmt::format("{}: line {}", path, line_no);
    const std::vector<std::string> fields = split_fields(line, where);
    if (t.indicators.empty()) {  // the header
      if (fields.size() < 2)
        throw std::invalid_argument(where + ": expected a header `name,I1,...,Im` with at least one indicator");
      t.indicators.assign(fields.begin() + 1, fields.end());
      for (std::size_t j = 0; j < t.indicators.size(); ++j)
        if (t.indicators[j].empty())
          throw std::invalid_argument(fmt::format("{}: indicator name {} is empty", where, j + 1));
      continue;
    }
    if (fields.size() != t.indicators.size() + 1)
      throw std::invalid_argument(fmt::format("{}: expected {} fields (a name and {} scores), got {}", where,
                                              t.indicators.size() + 1, t.indicators.size(), fields.size()));
    if (fields[0].empty()) throw std::invalid_argument(where + ": the object name (first field) is empty");
    std::vector<double> row;
    for (std::size_t j = 1; j < fields.size(); ++j) {
      std::size_t used = 0;
      double v = std::numeric_limits<double>::quiet_NaN();
      try {
        v = std::stod(fields[j], &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != fields[j].size() || fields[j].empty() || !std::isfinite(v))
        throw std::invalid_argument(fmt::format("{}, column {}: expected a finite number, got \"{}\"", where,
                                                t.indicators[j - 1], fields[j]));
      row.push_back(v);
    }
    t.objects.push_back(fields[0]);
    rows.push_back(row);
  }
  if (t.indicators.empty()) throw std::invalid_argument(path + ": the score file is empty");
  t.scores.resize(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(t.indicators.size()));
  for (std::size_t i = 0; i < rows.size(); ++i)
    for (std::size_t j = 0; j < rows[i].size(); ++j)
      t.scores(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = rows[i][j];
  t.lower_is_better.assign(t.indicators.size(), false);
  std::string why;
  if (!t.IsValid(&why)) throw std::invalid_argument(path + ": " + why);
  return t;
}

double normal_quantile(double p) {
  if (!(p > 0.0 && p < 1.0)) throw std::invalid_argument(fmt::format("normal_quantile: p = {} is not in (0, 1)", p));
  return boost::math::quantile(boost::math::normal_distribution<double>(0.0, 1.0), p);
}

std::vector<double> average_ranks(const std::vector<double>& values) {
  std::vector<std::size_t> order(values.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
  std::vector<double> ranks(values.size());
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    while (j + 1 < order.size() && values[order[j + 1]] == values[order[i]]) ++j;
    const double mean_rank = 0.5 * static_cast<double>(i + 1 + j + 1);  // ranks i+1 … j+1 share their mean
    for (std::size_t k = i; k <= j; ++k) ranks[order[k]] = mean_rank;
    i = j + 1;
  }
  return ranks;
}

RsrResult evaluate_rsr(const ScoreTable& table) {
  std::string why;
  if (!table.IsValid(&why)) throw std::invalid_argument("rsr: " + why);
  RsrResult r;
  r.table = table;
  const Eigen::Index n = table.scores.rows(), m = table.scores.cols();

  // Step 1 (Table 3): rank each indicator over the objects; the best object gets rank n.
  r.ranks.resize(n, m);
  for (Eigen::Index j = 0; j < m; ++j) {
    std::vector<double> column(static_cast<std::size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i)
      column[static_cast<std::size_t>(i)] = table.lower_is_better[static_cast<std::size_t>(j)] ? -table.scores(i, j)
                                                                                                 : table.scores(i, j);
    const std::vector<double> ranks = average_ranks(column);
    for (Eigen::Index i = 0; i < n; ++i) r.ranks(i, j) = ranks[static_cast<std::size_t>(i)];
  }

  // Step 2 (Table 4, eq. 36): RSR_i = Σ_j R_ij / (m·n).
  for (Eigen::Index i = 0; i < n; ++i)
    r.rsr.push_back(r.ranks.row(i).sum() / static_cast<double>(m * n));

  // Step 3 (Table 5): groups of equal RSR, ascending; the percentage of the last group is 1 − 1/(4n).
  std::vector<double> distinct = r.rsr;
  std::sort(distinct.begin(), distinct.end());
  distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
  int cumulative = 0;
  for (std::size_t g = 0; g < distinct.size(); ++g) {
    RsrGroup group;
    group.rsr = distinct[g];
    group.frequency = static_cast<int>(std::count(r.rsr.begin(), r.rsr.end(), distinct[g]));
    group.first_rank = cumulative + 1;
    cumulative += group.frequency;
    group.cumulative = cumulative;
    group.mean_rank = 0.5 * (group.first_rank + group.cumulative);
    group.corrected = g + 1 == distinct.size();
    const double p = group.corrected ? 1.0 - 1.0 / (4.0 * static_cast<double>(n))
                                     : group.mean_rank / static_cast<double>(n);
    group.percent = 100.0 * p;
    group.probit = 5.0 + normal_quantile(p);
    r.groups.push_back(group);
  }
  for (double v : r.rsr)
    r.group_of_object.push_back(
        static_cast<int>(std::lower_bound(distinct.begin(), distinct.end(), v) - distinct.begin()));
  if (r.groups.size() < 2)
    throw std::invalid_argument("rsr: every object has the same RSR; the regression of eq. 37 needs at least two "
                                "distinct values");

  // Step 4 (eq. 37): least squares of RSR_g on Probit_g over the groups.
  const auto k = static_cast<double>(r.groups.size());
  double mx = 0.0, my = 0.0;
  for (const auto& g : r.groups) {
    mx += g.probit / k;
    my += g.rsr / k;
  }
  double sxx = 0.0, sxy = 0.0, syy = 0.0;
  for (const auto& g : r.groups) {
    sxx += (g.probit - mx) * (g.probit - mx);
    sxy += (g.probit - mx) * (g.rsr - my);
    syy += (g.rsr - my) * (g.rsr - my);
  }
  r.slope = sxy / sxx;
  r.intercept = my - r.slope * mx;
  r.r_squared = syy > 0.0 ? sxy * sxy / (sxx * syy) : 1.0;
  for (int g : r.group_of_object) r.fitted_rsr.push_back(r.intercept + r.slope * r.groups[g].probit);

  // Step 5 (Table 6): Tian's three grades by Probit, carried to RSR through the regression.
  const double inf = std::numeric_limits<double>::infinity();
  r.grades = {{"poor", -inf, -inf, {}},
              {"good", 4.0, r.intercept + r.slope * 4.0, {}},
              {"excellent", 6.0, r.intercept + r.slope * 6.0, {}}};
  for (Eigen::Index i = 0; i < n; ++i) {
    const double fitted = r.fitted_rsr[static_cast<std::size_t>(i)];
    int grade = 0;
    for (int g = 1; g < static_cast<int>(r.grades.size()); ++g)
      if (fitted >= r.grades[g].rsr_from) grade = g;
    r.grade_of_object.push_back(grade);
    r.grades[grade].objects.push_back(table.objects[static_cast<std::size_t>(i)]);
  }
  return r;
}

namespace {

/// A score as given (shortest round-trip form), so the tables show the input unchanged.
std::string score_text(double v) { return fmt::format("{}", v); }

std::string rank_text(double v) { return v == std::floor(v) ? fmt::format("{:.0f}", v) : fmt::format("{:.1f}", v); }

std::string join(const std::vector<std::string>& items, const std::string& sep) {
  std::string s;
  for (std::size_t i = 0; i < items.size(); ++i) s += (i ? sep : "") + items[i];
  return s;
}

}  // namespace

std::string rsr_markdown(const RsrResult& r) {
  const ScoreTable& t = r.table;
  const std::size_t n = t.objects.size(), m = t.indicators.size();
  std::string header = "| object |", rule = "|---|";
  for (std::size_t j = 0; j < m; ++j) {
    header += " " + t.indicators[j] + (t.lower_is_better[j] ? " (lower is better)" : "") + " |";
    rule += "---|";
  }
  std::string md = "## Ranks (Table 3): score (rank), ties share their average rank\n\n" + header + "\n" + rule + "\n";
  std::string md4 = "## Rank-sum ratio (Table 4, eq. 36: RSR = Σ R / (m·n))\n\n" + header + " RSR |\n" + rule + "---|\n";
  for (std::size_t i = 0; i < n; ++i) {
    std::string row = "| " + t.objects[i] + " |";
    for (std::size_t j = 0; j < m; ++j)
      row += fmt::format(" {} ({}) |", score_text(t.scores(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j))),
                         rank_text(r.ranks(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j))));
    md += row + "\n";
    md4 += row + fmt::format(" {:.4f} |\n", r.rsr[i]);
  }
  md += "\n" + md4;
  md += fmt::format(
      "\n## RSR distribution (Table 5, n = {}): percent = R̄/n, last group (1 − 1/(4n)); Probit = 5 + Φ⁻¹(percent)\n\n"
      "| RSR | f | Σf | R | R̄ | percent | Probit |\n|---|---|---|---|---|---|---|\n",
      n);
  for (const auto& g : r.groups) {
    const std::string range =
        g.first_rank == g.cumulative ? fmt::format("{}", g.cumulative) : fmt::format("{}–{}", g.first_rank, g.cumulative);
    md += fmt::format("| {:.4f} | {} | {} | {} | {:.4f} | {:.1f}{} | {:.4f} |\n", g.rsr, g.frequency, g.cumulative,
                      range, g.mean_rank, g.percent, g.corrected ? " (1 − 1/(4n))" : "", g.probit);
  }
  md += fmt::format("\n## Regression (eq. 37), least squares over the {} groups\n\nRSR = {:.4f} + {:.4f} × Probit "
                    "(R² = {:.4f})\n\n| object | Probit | fitted RSR | grade |\n|---|---|---|---|\n",
                    r.groups.size(), r.intercept, r.slope, r.r_squared);
  for (std::size_t i = 0; i < n; ++i)
    md += fmt::format("| {} | {:.4f} | {:.4f} | {} |\n", t.objects[i], r.groups[r.group_of_object[i]].probit,
                      r.fitted_rsr[i], r.grades[r.grade_of_object[i]].name);
  md += "\n## Grading (Table 6): Tian's three grades\n\n| grade | Probit | RSR | objects |\n|---|---|---|---|\n";
  for (std::size_t g = 0; g < r.grades.size(); ++g) {
    const RsrGrade& grade = r.grades[g];
    const std::string objects = grade.objects.empty() ? "none" : join(grade.objects, ", ");
    if (g == 0)
      md += fmt::format("| {} | < {:.0f} | < {:.4f} | {} |\n", grade.name, r.grades[1].probit_from,
                        r.grades[1].rsr_from, objects);
    else
      md += fmt::format("| {} | ≥ {:.0f} | ≥ {:.4f} | {} |\n", grade.name, grade.probit_from, grade.rsr_from, objects);
  }
  return md;
}

nlohmann::json rsr_json(const RsrResult& r) {
  using nlohmann::json;
  const ScoreTable& t = r.table;
  json objects = json::array();
  for (std::size_t i = 0; i < t.objects.size(); ++i) {
    json scores = json::object(), ranks = json::object();
    for (std::size_t j = 0; j < t.indicators.size(); ++j) {
      scores[t.indicators[j]] = t.scores(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
      ranks[t.indicators[j]] = r.ranks(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
    }
    objects.push_back({{"name", t.objects[i]},
                       {"scores", scores},
                       {"ranks", ranks},
                       {"rsr", r.rsr[i]},
                       {"probit", r.groups[r.group_of_object[i]].probit},
                       {"fitted_rsr", r.fitted_rsr[i]},
                       {"grade", r.grades[r.grade_of_object[i]].name}});
  }
  json groups = json::array();
  for (const auto& g : r.groups)
    groups.push_back({{"rsr", g.rsr},
                      {"f", g.frequency},
                      {"cumulative_f", g.cumulative},
                      {"rank_from", g.first_rank},
                      {"rank_to", g.cumulative},
                      {"mean_rank", g.mean_rank},
                      {"percent", g.percent},
                      {"corrected_last_group", g.corrected},
                      {"probit", g.probit}});
  json grades = json::array();
  for (std::size_t g = 0; g < r.grades.size(); ++g)
    grades.push_back({{"grade", r.grades[g].name},
                      {"probit_from", g == 0 ? json(nullptr) : json(r.grades[g].probit_from)},
                      {"rsr_from", g == 0 ? json(nullptr) : json(r.grades[g].rsr_from)},
                      {"objects", r.grades[g].objects}});
  json lower = json::array();
  for (std::size_t j = 0; j < t.indicators.size(); ++j)
    if (t.lower_is_better[j]) lower.push_back(t.indicators[j]);
  return {{"n_objects", t.objects.size()},
          {"n_indicators", t.indicators.size()},
          {"indicators", t.indicators},
          {"lower_is_better", lower},
          {"objects", objects},
          {"distribution", groups},
          {"regression", {{"intercept", r.intercept}, {"slope", r.slope}, {"r_squared", r.r_squared},
                          {"fit", "least squares of RSR on Probit over the distinct RSR values"}}},
          {"grades", grades}};
}

}  // namespace experiments
