#include "experiments/comparator/compare_metrics.hpp"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

namespace experiments {

std::size_t SampleDiagnostics::num_flagged() const {
  std::size_t n = 0;
  for (std::size_t i = 0; i < edge_distance.size(); ++i) n += flagged(i);
  return n;
}

std::vector<bool> SampleDiagnostics::unflagged_mask() const {
  std::vector<bool> mask(edge_distance.size());
  for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = !flagged(i);
  return mask;
}

SampleDiagnostics diagnose_samples(const Eigen::MatrixXd& points, const Eigen::Vector3d& load_centre,
                                   double load_radius, const std::optional<core::RuledSurface>& cut,
                                   const SampleFlagRules& rules) {
  SampleDiagnostics d;
  for (Eigen::Index i = 0; i < points.rows(); ++i) {
    const Eigen::Vector3d x = points.row(i).transpose();
    // The traction jumps from force/area to 0 on the patch circle: a point-wise value there depends on how
    // each discretisation facets the circle, not on the method.
    const double edge = std::abs((x - load_centre).norm() - load_radius);
    d.edge_distance.push_back(edge);
    d.on_patch_edge.push_back(edge < rules.patch_edge_distance);
    if (cut) {
      const double dc = cut->distance(x);
      d.cut_distance.emplace_back(dc);
      d.near_cut.push_back(dc < rules.cut_distance);
    } else {
      d.cut_distance.emplace_back(std::nullopt);
      d.near_cut.push_back(false);
    }
  }
  return d;
}

double rmse(const Eigen::MatrixXd& u, const Eigen::MatrixXd& u_reference, const std::vector<bool>& include) {
  double sum = 0.0;
  int n = 0;
  for (Eigen::Index i = 0; i < u.rows(); ++i) {
    if (!include.empty() && !include[static_cast<std::size_t>(i)]) continue;
    sum += (u.row(i) - u_reference.row(i)).squaredNorm();  // eq. 34: the squared distance of the two positions
    ++n;
  }
  return n == 0 ? std::numeric_limits<double>::quiet_NaN() : std::sqrt(sum / n);
}

double peak_magnitude(const Eigen::MatrixXd& u) { return u.rows() == 0 ? 0.0 : u.rowwise().norm().maxCoeff(); }

double ReferenceErrorBar::extrapolated_rms_mm() const {
  if (!extrapolated_samples) throw std::logic_error("ReferenceErrorBar::extrapolated_rms_mm: no extrapolated samples");
  const Eigen::MatrixXd& x = *extrapolated_samples;
  return extrapolated_relative * x.norm() * 1e3 / std::sqrt(static_cast<double>(x.rows()));
}

nlohmann::json ReferenceErrorBar::to_json() const {
  if (!known) return {{"known", false}, {"why_unknown", why_unknown}, {"source", source}};
  return {{"known", true}, {"rms_mm", rms_mm}, {"relative", relative}, {"method", method}, {"source", source}};
}

std::optional<Eigen::MatrixXd> sample_rows(const nlohmann::json& rows) {
  if (!rows.is_array()) return std::nullopt;
  Eigen::MatrixXd m(static_cast<Eigen::Index>(rows.size()), 3);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!rows[i].is_array() || rows[i].size() != 3) return std::nullopt;
    for (std::size_t k = 0; k < 3; ++k) {
      if (!rows[i][k].is_number()) return std::nullopt;
      m(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k)) = rows[i][k].get<double>();
    }
  }
  return m;
}

std::string estimate_method(const nlohmann::json& richardson) {
  if (richardson.contains("observed_order"))
    return fmt::format("Richardson extrapolation over the study's last three levels (observed order {:.2f})",
                       richardson["observed_order"].get<double>());
  return richardson.value("note", std::string("the study's estimate"));
}

ReferenceErrorBar reference_error_bar(const nlohmann::json& verify_fem, const std::string& source,
                                      const std::string& case_name, double mesh_size,
                                      const Eigen::MatrixXd& fem_samples) {
  ReferenceErrorBar bar;
  bar.source = source;
  const auto unknown = [&](const std::string& why) {
    bar.why_unknown = why;
    return bar;
  };
  const nlohmann::json* study = nullptr;
  if (verify_fem.contains("mesh_convergence") && verify_fem["mesh_convergence"].contains(case_name))
    study = &verify_fem["mesh_convergence"][case_name];
  if (!study) return unknown(fmt::format("{} holds no mesh study of case '{}'", source, case_name));
  // The level solved at this reference's mesh size: the study's finest (its error is the study's estimate) or a
  // coarser one, whose error is measured against the finest: ‖U_h − U‖ ≤ ‖U_h − U_f‖ + ‖U_f − U‖.
  const nlohmann::json* finest = nullptr;
  const nlohmann::json* level_h = nullptr;
  if (study->contains("levels") && (*study)["levels"].is_array())
    for (const auto& level : (*study)["levels"]) {
      if (level.contains("error") || !level.contains("sample_displacements_mm")) continue;
      finest = &level;
      if (std::abs(level.value("mesh_size_mm", 0.0) - mesh_size * 1e3) <= 1e-9) level_h = &level;
    }
  if (!finest) return unknown(fmt::format("the study of '{}' in {} has no solved level", case_name, source));
  const double finest_size = finest->value("mesh_size_mm", 0.0);
  if (!level_h)
    return unknown(fmt::format("the study solved no level at {} mm, this reference's mesh size (its finest level is "
                               "{} mm)",
                               mesh_size * 1e3, finest_size));
  auto samples_of = [&](const nlohmann::json& level) -> std::optional<Eigen::MatrixXd> {
    std::optional<Eigen::MatrixXd> u = sample_rows(level["sample_displacements_mm"]);
    if (u && u->rows() != fem_samples.rows()) u.reset();
    return u;
  };
  const std::optional<Eigen::MatrixXd> study_u = samples_of(*level_h), finest_u = samples_of(*finest);
  if (!study_u || !finest_u)
    return unknown(fmt::format("the study has {} samples, this run {}", (*level_h)["sample_displacements_mm"].size(),
                               fem_samples.rows()));
  const Eigen::MatrixXd u_mm = fem_samples * 1e3;
  const double difference = (*study_u - u_mm).norm() / u_mm.norm();
  if (!(difference <= 1e-6))
    return unknown(fmt::format("the study's {} mm samples differ from this run's by {:.3g} (relative): it solved "
                               "another case or build",
                               mesh_size * 1e3, difference));
  const nlohmann::json richardson = study->value("richardson", nlohmann::json::object());
  if (!richardson.contains("estimated_error_of_finest_relative"))
    return unknown(fmt::format("the study of '{}' has no error estimate ({})", case_name,
                               richardson.value("note", std::string("fewer than three solved levels"))));
  const double finest_relative = richardson["estimated_error_of_finest_relative"].get<double>();
  const std::string finest_method = estimate_method(richardson);
  bar.known = true;
  if (richardson.contains("extrapolated_sample_displacements_mm")) {
    nlohmann::json level = {{"sample_displacements_mm", richardson["extrapolated_sample_displacements_mm"]}};
    if (const std::optional<Eigen::MatrixXd> x = samples_of(level)) {
      bar.extrapolated_samples = *x * 1e-3;
      bar.extrapolated_relative = finest_relative * finest_u->norm() / x->norm();
      bar.extrapolated_method = fmt::format("the samples extrapolated from the study's last two levels ({}); their "
                                            "bar is the finest level's ({} mm) estimated error",
                                            finest_method, finest_size);
    }
  }
  if (level_h == finest) {
    bar.relative = finest_relative;
    bar.method = finest_method;
  } else {
    const double to_finest = (*study_u - *finest_u).norm();
    const double finest_error = finest_relative * finest_u->norm();
    bar.relative = (to_finest + finest_error) / u_mm.norm();
    bar.method = fmt::format(
        "measured against the study's finest level, {} mm ({:.2f} % of this reference), plus that level's own "
        "error ({:.2f} %: {})",
        finest_size, 100.0 * to_finest / u_mm.norm(), 100.0 * finest_relative, finest_method);
  }
  // The study's relative error is over the norm of all sample displacements: as an RMS per sample it is
  // relative · ‖U‖ / √n, the same measure as eq. 34.
  bar.rms_mm = bar.relative * u_mm.norm() / std::sqrt(static_cast<double>(u_mm.rows()));
  return bar;
}

}  // namespace experiments
