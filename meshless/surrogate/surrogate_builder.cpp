#include "meshless/surrogate/surrogate_builder.hpp"

#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <stdexcept>

namespace meshless {
namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

SurrogateFitOptions fit_options(const core::SurrogateSpec& spec) {
  SurrogateFitOptions o;
  o.max_force_order = spec.max_force_order;
  o.max_tangential_order = spec.max_tangential_order;
  o.max_normal_order = spec.max_normal_order;
  o.max_contact_order = spec.max_contact_order;
  o.contact_length = spec.contact_length;
  o.cv_folds = spec.cv_folds;
  return o;
}

std::vector<double> training_levels(const core::SurrogateSpec& spec) {
  std::vector<double> levels;
  for (int m = spec.force_levels; m >= 1; --m) levels.push_back(-spec.max_force * m / spec.force_levels);
  for (int m = 1; m <= spec.force_levels; ++m) levels.push_back(spec.max_force * m / spec.force_levels);
  return levels;
}

std::vector<PatchLoad> holdout_loads(const core::SurrogateSpec& spec, const std::vector<int>& contacts) {
  std::vector<PatchLoad> loads;
  if (contacts.empty()) return loads;
  for (int i = 0; i < spec.holdout_forces; ++i) {
    PatchLoad l;
    l.contact = contacts[i % contacts.size()];
    const int k = i / 2;
    if (i % 2 == 0) {
      // One axis, half-way between the two middle trained levels, alternating sign.
      const int m = spec.force_levels / 2;
      const double magnitude = spec.max_force * (m + 0.5) / spec.force_levels;
      l.force[k % 3] = (k % 2 == 0 ? -1.0 : 1.0) * magnitude;
    } else {
      // Oblique, half the trained range: every component in range, all three superposed.
      const double z = 0.6 * std::cos(1.3 * (k + 1));
      const double angle = 2.399963 * (k + 1);  // golden angle
      const double r = std::sqrt(1.0 - z * z);
      l.force = 0.5 * spec.max_force * Eigen::Vector3d(r * std::cos(angle), r * std::sin(angle), z);
    }
    loads.push_back(l);
  }
  return loads;
}

std::vector<PatchLoad> region_holdout_loads(const core::SurrogateSpec& spec, const std::vector<int>& nodes) {
  std::vector<PatchLoad> loads;
  for (int node : nodes)
    for (const PatchLoad& l : holdout_loads(spec, {node})) loads.push_back(l);
  return loads;
}

std::vector<HoldoutError> holdout_errors(const Surrogate& surrogate, const std::vector<PatchLoad>& loads,
                                         const std::vector<SolvedLoad>& full, const std::vector<char>* near_cut) {
  if (loads.size() != full.size())
    throw std::invalid_argument("holdout_errors: one full solve per load expected");
  std::vector<HoldoutError> out;
  core::PointMatrix u;
  for (std::size_t i = 0; i < loads.size(); ++i) {
    const Eigen::Vector3d x = surrogate.data().surface_position.row(loads[i].contact).transpose();
    const SurrogateResponse r = surrogate.query(x, loads[i].force, &u);
    if (r.contact_node != loads[i].contact)
      throw std::logic_error("holdout_errors: the held-out contact is not a trained contact node");
    HoldoutError e;
    e.load = loads[i];
    const core::PointMatrix& f = full[i].displacement;
    e.rmse = std::sqrt((u - f).rowwise().squaredNorm().mean());  // eq. 34 over the surface nodes
    e.contact_displacement = f.row(loads[i].contact).norm();
    e.relative = e.contact_displacement > 0.0 ? e.rmse / e.contact_displacement : 0.0;
    e.contact_error = (r.contact_displacement - f.row(loads[i].contact).transpose()).norm();
    if (near_cut) {
      double near = 0.0, away = 0.0;
      int n_near = 0, n_away = 0;
      for (Eigen::Index k = 0; k < u.rows(); ++k) {
        const double e2 = (u.row(k) - f.row(k)).squaredNorm();
        if ((*near_cut)[k]) {
          near += e2;
          ++n_near;
        } else {
          away += e2;
          ++n_away;
        }
      }
      if (n_near) e.rmse_near_cut = std::sqrt(near / n_near);
      if (n_away) e.rmse_away_from_cut = std::sqrt(away / n_away);
    }
    e.trained_contact = false;
    for (const ContactFit& c : surrogate.data().contacts) e.trained_contact |= c.contact == loads[i].contact;
    out.push_back(e);
  }
  return out;
}

SurrogateData build_surrogate(const EfgProblem& problem, const core::SurrogateSpec& spec,
                              const SurrogateBuildOptions& options,
                              const std::function<void(const std::string&)>& progress,
                              SurrogateBuildReport* report) {
  const SurrogateFitOptions fit = fit_options(spec);
  std::string invalid;
  if (!fit.IsValid(&invalid)) throw std::invalid_argument("surrogate: " + invalid);
  SurrogateBuildReport rep;
  const SurfaceNodes surface = surface_nodes(problem.mesh);
  PatchSolveOptions solve;
  solve.patch_radius = spec.patch_radius;
  solve.smooth_profile = spec.patch_profile == core::SurrogateSpec::PatchProfile::smooth;
  solve.response_step = response_step(problem, spec.response_time == core::SurrogateSpec::ResponseTime::end);
  solve.memory_budget_bytes = options.memory_budget_bytes;
  solve.max_workers = options.max_workers;

  SurrogateData d;
  d.max_force = spec.max_force;
  d.levels = training_levels(spec);
  d.patch_radius = spec.patch_radius;
  d.patch_profile = solve.smooth_profile ? "smooth" : "uniform";
  d.response_time = spec.response_time == core::SurrogateSpec::ResponseTime::end ? "end" : "end_of_ramp";
  d.response_seconds = problem.step_times[solve.response_step - 1];
  d.surface_vertex = surface.vertex;
  d.surface_position = surface.position;

  // 1. Contact nodes: each contact point snapped to its nearest surface node, or a region's spread nodes.
  std::vector<int> contacts;
  if (spec.contact_region) {
    const core::ContactRegionSpec& g = *spec.contact_region;
    rep.region = select_region_contacts(surface, g.centre, g.radius, g.training_contacts, g.holdout_contacts);
    contacts = rep.region.training;
    rep.snap_distance = {rep.region.centre_snap_distance};
    ContactRegion region;
    region.centre = surface.position.row(rep.region.centre_node).transpose();
    region.normal = surface.normal.row(rep.region.centre_node).transpose();
    region.radius = g.radius;
    d.region = region;
    if (progress)
      progress(fmt::format("contact region: {} surface nodes within {:.4g} mm of the centre node ({:.3g} mm from "
                           "the configured centre): {} trained, {} held out",
                           rep.region.region_nodes, g.radius * 1e3, rep.region.centre_snap_distance * 1e3,
                           contacts.size(), rep.region.holdout.size()));
  }
  for (const Eigen::Vector3d& p : spec.contact_region ? std::vector<Eigen::Vector3d>{} : spec.contact_points) {
    double distance = 0.0;
    const int c = surface.nearest(p, &distance);
    for (int previous : contacts)
      if (previous == c)
        throw std::invalid_argument(fmt::format(
            "two contact points snap to the same surface node ({:.4g}, {:.4g}, {:.4g}) mm; expected distinct "
            "points "
            "at least a node spacing apart",
            1e3 * surface.position(c, 0), 1e3 * surface.position(c, 1), 1e3 * surface.position(c, 2)));
    contacts.push_back(c);
    rep.snap_distance.push_back(distance);
  }

  // 2. The full model at every contact, axis and level.
  std::vector<PatchLoad> loads;
  for (int c : contacts)
    for (int j = 0; j < 3; ++j)
      for (double level : d.levels) {
        PatchLoad l;
        l.contact = c;
        l.force[j] = level;
        loads.push_back(l);
      }
  rep.training_solves = static_cast<int>(loads.size());
  const std::vector<SolvedLoad> solved =
      solve_patch_loads(problem, options.efg, surface, loads, solve, progress, &rep.training);

  // 3. The fits, one contact at a time.
  const auto t_fit = std::chrono::steady_clock::now();
  const int nl = static_cast<int>(d.levels.size());
  for (std::size_t ci = 0; ci < contacts.size(); ++ci) {
    ContactTrainingData data;
    data.contact = contacts[ci];
    data.levels = d.levels;
    for (int j = 0; j < 3; ++j)
      for (int l = 0; l < nl; ++l) {
        const SolvedLoad& s = solved[(ci * 3 + j) * nl + l];
        data.displacement[j].push_back(s.displacement);
        rep.peak_contact_displacement =
            std::max(rep.peak_contact_displacement, s.displacement.row(contacts[ci]).norm());
      }
    const auto t0 = std::chrono::steady_clock::now();
    d.contacts.push_back(fit_contact(surface, data, spec.max_force, fit));
    rep.training_data.push_back(std::move(data));
    if (progress) {
      const ContactFit& f = d.contacts.back();
      std::string orders;
      for (int j = 0; j < 3; ++j) {
        const AxisFit& a = f.axis[j];
        orders += fmt::format("{}{}: lambda {} (CV {:.3g} mm), field lambda {} (CV {:.3g} mm), (a,b,c)",
                              j ? "; " : "", "xyz"[j], a.force_order, a.contact_cv_rms * 1e3, a.field_order,
                              a.field_order_cv_rms * 1e3);
        for (const InducedFieldFit& field : a.field)
          orders += fmt::format(" ({},{},{}) CV {:.3g} mm", field.tangential_order, field.normal_order,
                                field.contact_order, field.cv_rms * 1e3);
      }
      progress(fmt::format("fit contact {}/{}: {} ({:.1f} s)", ci + 1, contacts.size(), orders,
                           seconds_since(t0)));
    }
  }
  if (d.region) {
    const auto t0 = std::chrono::steady_clock::now();
    d.region_field = fit_region_field(surface, *d.region, rep.training_data, spec.max_force, region_shape(d.contacts),
                                      spec.contact_region->position_order, fit);
    if (progress)
      progress(fmt::format("fit the region's eq. 28 (position degree {}) over {} contacts: training RMS {:.3g} mm "
                           "({:.1f} s)",
                           d.region_field->position_order, d.contacts.size(), d.region_field->training_rms * 1e3,
                           seconds_since(t0)));
  }
  rep.fit_seconds = seconds_since(t_fit);

  // 4. Held-out forces: at the trained contacts, and at the region's untrained nodes.
  std::vector<PatchLoad> holdout = holdout_loads(spec, contacts);
  for (const PatchLoad& l : region_holdout_loads(spec, rep.region.holdout)) holdout.push_back(l);
  if (!holdout.empty()) {
    const std::vector<SolvedLoad> full = solve_patch_loads(
        problem, options.efg, surface, holdout, solve,
        [&](const std::string& line) {
          if (progress) progress("held-out " + line);
        },
        &rep.holdout);
    const Surrogate surrogate(d);
    // On a cut body, the error near the lips (within one node spacing of the cut) and away from them.
    std::vector<char> near_cut;
    if (problem.cut) {
      rep.near_cut_distance = problem.node_spacing;
      for (int k = 0; k < surface.size(); ++k)
        near_cut.push_back(problem.cut->distance(surface.position.row(k).transpose()) <= rep.near_cut_distance);
    }
    rep.holdouts = holdout_errors(surrogate, holdout, full, problem.cut ? &near_cut : nullptr);
    rep.holdout_loads = holdout;
    rep.holdout_solves = full;
  }

  // The report kept in the file (for people; queries never read it).
  nlohmann::json holdouts = nlohmann::json::array();
  for (const HoldoutError& e : rep.holdouts)
    holdouts.push_back(
        {{"surface_node", e.load.contact},
         {"force_N", {e.load.force.x(), e.load.force.y(), e.load.force.z()}},
         {"rmse_m", e.rmse},
         {"contact_displacement_m", e.contact_displacement},
         {"rmse_relative_to_contact_displacement", e.relative},
         {"rmse_relative_to_peak_contact_displacement", e.rmse / rep.peak_contact_displacement},
         {"contact_error_m", e.contact_error},
         {"trained_contact", e.trained_contact},
         {"rmse_near_cut_m", std::isnan(e.rmse_near_cut) ? nlohmann::json() : nlohmann::json(e.rmse_near_cut)},
         {"rmse_away_from_cut_m",
          std::isnan(e.rmse_away_from_cut) ? nlohmann::json() : nlohmann::json(e.rmse_away_from_cut)}});
  std::vector<double> snap_mm;
  for (double s : rep.snap_distance) snap_mm.push_back(s * 1e3);
  d.report = {{"training",
               {{"solves", rep.training_solves},
                {"workers", rep.training.workers},
                {"model_bytes", rep.training.model_bytes},
                {"setup_seconds", rep.training.setup_seconds},
                {"wall_seconds", rep.training.wall_seconds},
                {"response_step", solve.response_step},
                {"surface_nodes", surface.size()},
                {"contact_snap_distance_mm", snap_mm}}},
              {"fit_seconds", rep.fit_seconds},
              {"peak_contact_displacement_m", rep.peak_contact_displacement},
              {"holdout", holdouts},
              {"holdout_wall_seconds", rep.holdout.wall_seconds}};
  if (d.region) {
    auto positions_mm = [&](const std::vector<int>& nodes) {
      nlohmann::json a = nlohmann::json::array();
      for (int s : nodes)
        a.push_back({1e3 * surface.position(s, 0), 1e3 * surface.position(s, 1), 1e3 * surface.position(s, 2)});
      return a;
    };
    d.report["contact_region"] = {{"region_nodes", rep.region.region_nodes},
                                  {"field_training_rms_m", d.region_field->training_rms},
                                  {"training_contacts_mm", positions_mm(rep.region.training)},
                                  {"holdout_contacts_mm", positions_mm(rep.region.holdout)}};
  }
  if (report) *report = rep;
  return d;
}

}  // namespace meshless
