#include "experiments/models/model_result.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <stdexcept>

namespace experiments {

void describe_samples_near_cut(const core::Geometry& g, ModelResult* r) {
  r->sample_cut_distance.clear();
  r->sample_lip.clear();
  if (!g.cut) return;
  for (Eigen::Index i = 0; i < g.sample_points.rows(); ++i) {
    const Eigen::Vector3d x = g.sample_points.row(i).transpose();
    r->sample_cut_distance.push_back(g.cut->distance(x));
    r->sample_lip.push_back(g.cut->frame(x).behind_front ? g.cut->side(x) : 0);
  }
}


void write_samples_csv(const std::string& path, const ModelResult& r) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << "sample,x_mm,y_mm,z_mm,ux_mm,uy_mm,uz_mm,magnitude_mm,cut_distance_mm,lip\n";
  const bool cut = !r.sample_cut_distance.empty();
  for (Eigen::Index i = 0; i < r.sample_points.rows(); ++i) {
    const Eigen::Vector3d x = r.sample_points.row(i).transpose() * 1e3;
    const Eigen::Vector3d u = r.sample_displacements.row(i).transpose() * 1e3;
    // eq. 33: the displacement of a sample is the distance between its deformed and original positions.
    out << fmt::format("{},{:.6f},{:.6f},{:.6f},{:.9g},{:.9g},{:.9g},{:.9g},{},{}\n", i, x(0), x(1), x(2), u(0), u(1),
                       u(2), u.norm(), cut ? fmt::format("{:.6f}", r.sample_cut_distance[i] * 1e3) : std::string(),
                       cut ? r.sample_lip[i] : 0);
  }
  out.close();
  if (!out) throw std::runtime_error("writing " + path + " failed (disk full?)");
}

nlohmann::json timings_json(const ModelResult& r) {
  nlohmann::json j;
  j["model"] = r.model;
  j["setup_seconds"] = r.setup_seconds;
  j["total_seconds"] = r.total_seconds;
  double assembly = 0.0, solve = 0.0;
  int iterations = 0, cutbacks = 0;
  double smallest_margin = 1.0;
  nlohmann::json steps = nlohmann::json::array();
  auto attempts_json = [](const std::vector<core::NewtonAttempt>& list) {
    nlohmann::json attempts = nlohmann::json::array();
    for (const core::NewtonAttempt& a : list)
      attempts.push_back({{"t_start", a.t_start},
                          {"t_end", a.t_end},
                          {"newton_iterations", a.iterations},
                          {"relative_residuals", a.residuals},
                          {"failure", a.failure}});
    return attempts;
  };
  for (const auto& s : r.steps) {
    const nlohmann::json attempts = attempts_json(s.failed_attempts);
    cutbacks += static_cast<int>(s.failed_attempts.size());
    smallest_margin = std::min(smallest_margin, s.admissibility_margin);
    assembly += s.assembly_seconds;
    solve += s.solve_seconds;
    iterations += s.iterations;
    steps.push_back({{"step", s.step},
                     {"time", s.time},
                     {"wall_seconds", s.wall_seconds},
                     {"assembly_seconds", s.assembly_seconds},
                     {"solve_seconds", s.solve_seconds},
                     {"newton_iterations", s.iterations},
                     {"linear_iterations", s.linear_iterations},
                     {"relative_residuals", s.residuals},
                     {"min_one_plus_2k_lambda", s.admissibility_margin},
                     {"substeps", s.substeps},
                     {"cutbacks", static_cast<int>(s.failed_attempts.size())},
                     {"failed_attempts", attempts},
                     {"retried_plain_attempts", attempts_json(s.retried_plain)},
                     {"rejected_mixes", s.rejected_mixes}});
  }
  j["assembly_seconds"] = assembly;
  j["solve_seconds"] = solve;
  j["newton_iterations_total"] = iterations;
  j["cutbacks_total"] = cutbacks;  // failed Newton attempts whose step was halved and retried
  j["min_one_plus_2k_lambda"] = smallest_margin;  // over the converged steps; > 0 inside the admissible range
  j["steps"] = steps;
  j["details"] = r.details;
  return j;
}

nlohmann::json admissibility_json(const core::SmallestMargin& m, const core::KelvinParameters& law) {
  const Eigen::Vector3d x = m.point * 1e3;
  const double k = law.k;
  const std::string measure =
      "smallest 1 + 2k lambda over principal strains lambda and integration points, at the converged states "
      "(docs/MATERIAL.md); ";
  return {{"measure", measure + (law.slope_floor > 0.0
                                     ? "below slope_floor the law was continued past the paper's range there (§1.7)"
                                     : "the strain must keep it > 0")},
          {"min_one_plus_2k_lambda", m.margin},
          {"slope_floor", law.slope_floor},
          {"k", k},
          {"limit_principal_strain", k == 0.0 ? nlohmann::json(nullptr) : nlohmann::json(-1.0 / (2.0 * k))},
          {"time", m.time},
          {"point_mm", {x.x(), x.y(), x.z()}},
          {"strain", {m.strain[0], m.strain[1], m.strain[2], m.strain[3], m.strain[4], m.strain[5]}}};
}

void write_timings_json(const std::string& path, const ModelResult& r) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << timings_json(r).dump(2) << "\n";
  out.close();
  if (!out) throw std::runtime_error("writing " + path + " failed (disk full?)");
}

void write_text_file(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error("cannot open " + path + " for writing");
  out << text;
  out.close();
  if (!out) throw std::runtime_error("writing " + path + " failed (disk full?)");
}

}  // namespace experiments
