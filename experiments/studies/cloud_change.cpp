#include "experiments/studies/cloud_change.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

namespace experiments {

using json = nlohmann::json;

json CloudChange::to_json() const {
  json j = {{"known", known}, {"runs", runs}};
  if (known) {
    j["mm"] = mm;
    j["measure"] = measure;
  } else {
    j["why_unknown"] = why_unknown;
  }
  return j;
}

namespace {

/// A model's RMSE [mm] in a comparison summary (against the extrapolated samples when `versus_extrapolated`), or a
/// negative value when it did not solve there.
double rmse_of(const json& summary, const std::string& name, bool versus_extrapolated) {
  const json models = versus_extrapolated
                          ? summary.value("versus_extrapolated", json::object()).value("models", json::object())
                          : summary.value("models", json::object());
  if (!models.contains(name) || !models.at(name).value("rmse_mm", json()).is_number()) return -1.0;
  return models.at(name).at("rmse_mm").get<double>();
}

}  // namespace

CloudChange cloud_change(const std::vector<std::string>& study_dirs, const CloudChangeBaseline& row) {
  namespace fs = std::filesystem;
  CloudChange result;
  if (study_dirs.empty()) {
    result.why_unknown = "no cloud study named for this case (the plan's /table1/N/cloud_studies)";
    return result;
  }
  const double this_difference = row.proposed_rmse_mm - row.baseline_rmse_mm;
  double both = -1.0, one = -1.0;
  std::size_t missing = 0;  // study folders without a runs/ folder
  for (const std::string& dir : study_dirs) {
    if (!fs::is_directory(fs::path(dir) / "runs")) {
      ++missing;
      continue;
    }
    std::vector<fs::path> folders;
    for (const auto& entry : fs::directory_iterator(fs::path(dir) / "runs"))
      if (fs::is_regular_file(entry.path() / "summary.json")) folders.push_back(entry.path());
    std::sort(folders.begin(), folders.end());  // the same order on every machine
    for (const fs::path& folder : folders) {
      // As the reader would type it from here, however the plan's path was given (absolute or relative).
      std::error_code ec;
      const fs::path shown = fs::proximate(folder, ec);
      json run = {{"run", ec ? folder.string() : shown.string()}};
      std::ifstream in(folder / "summary.json");
      const json s = json::parse(in, nullptr, false);
      if (s.is_discarded() || !s.contains("reference")) {
        run["unused"] = "its summary.json is not a comparison";
        result.runs.push_back(run);
        continue;
      }
      const double peak = s.at("reference").value("peak_sample_displacement_mm", 0.0);
      if (!(std::abs(peak - row.reference_peak_mm) <= 1e-9 * std::abs(row.reference_peak_mm))) {
        run["unused"] = fmt::format("another reference (peak {:.6g} mm, this row's {:.6g} mm)", peak,
                                    row.reference_peak_mm);
        result.runs.push_back(run);
        continue;
      }
      if (row.versus_extrapolated && !s.contains("versus_extrapolated")) {
        run["unused"] = "no RMSEs against the extrapolated FEM (a run from before compare wrote them, or without the "
                        "mesh study; rerun its sweep)";
        result.runs.push_back(run);
        continue;
      }
      if (row.versus_extrapolated) {
        // The extrapolated samples are identified by their bar: a run scored against another mesh study's
        // extrapolation (a sweep run before the row's reference_family was chosen) measures another distance.
        const double bar = s.at("versus_extrapolated").value("error_bar_mm", 0.0);
        if (!(std::abs(bar - row.extrapolated_bar_mm) <= 1e-9 * std::abs(row.extrapolated_bar_mm))) {
          run["unused"] = fmt::format("scored against another mesh study's extrapolated samples (their bar {:.6g} mm, "
                                      "this row's {:.6g} mm)",
                                      bar, row.extrapolated_bar_mm);
          result.runs.push_back(run);
          continue;
        }
      }
      const double p = rmse_of(s, row.proposed, row.versus_extrapolated),
                   b = rmse_of(s, row.baseline, row.versus_extrapolated);
      for (const std::string& name : {row.proposed, row.baseline}) {
        const double rmse = name == row.proposed ? p : b;
        const json& details =
            s.value("models", json::object()).value(name, json::object()).value("details", json());
        run[name] = rmse >= 0.0 ? json{{"rmse_mm", rmse}, {"n_nodes", details.value("n_nodes", json())}}
                                : json{{"not_solved", s.value("not_solved", json::object())
                                                          .value(name, json::object())
                                                          .value("why", std::string("not in this run"))}};
      }
      if (p >= 0.0) one = std::max(one, std::abs(p - row.proposed_rmse_mm));
      if (b >= 0.0) one = std::max(one, std::abs(b - row.baseline_rmse_mm));
      if (p >= 0.0 && b >= 0.0) both = std::max(both, std::abs((p - b) - this_difference));
      result.runs.push_back(run);
    }
  }
  if (both >= 0.0 || one >= 0.0) {
    result.known = true;
    result.mm = both >= 0.0 ? both : one;
    result.measure = both >= 0.0 ? "difference" : "one model's RMSE";
  } else {
    result.why_unknown =
        missing == study_dirs.size()
            ? fmt::format("no results in {} (run its sweep: `tissue sweep configs/sweeps/<name>.json`)",
                          study_dirs.front())
            : "no run of the cloud studies solved either model against this reference";
  }
  return result;
}

}  // namespace experiments
