#include "experiments/comparator/mesh_family_error_bar.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>

namespace experiments {
namespace {

using nlohmann::json;

bool is_discretisation_key(const std::string& pointer) {
  return std::any_of(kDiscretisationKeys.begin(), kDiscretisationKeys.end(), [&](const std::string& key) {
    return pointer == key || pointer.rfind(key + "/", 0) == 0;
  });
}

/// A sample array of a study ([mm], sample_rows) in metres; nullopt when it is not one.
std::optional<Eigen::MatrixXd> rows_in_metres(const json& rows) {
  std::optional<Eigen::MatrixXd> m = sample_rows(rows);
  if (m) *m *= 1e-3;
  return m;
}

/// The case file a study records, as given when it exists, else relative to the source tree (studies record the
/// path they were run with, from the repository's root).
std::string resolve_config(const std::string& recorded) {
  if (std::filesystem::exists(recorded)) return recorded;
  const std::filesystem::path in_tree = std::filesystem::path(TISSUE_SOURCE_DIR) / recorded;
  if (std::filesystem::path(recorded).is_relative() && std::filesystem::exists(in_tree)) return in_tree.string();
  return {};
}

}  // namespace

std::string first_problem_difference(const json& a, const json& b) {
  for (const json& op : json::diff(a, b)) {
    const std::string path = op.at("path").get<std::string>();
    if (!is_discretisation_key(path)) return path;
  }
  return {};
}

MeshFamily read_mesh_family(const std::vector<std::string>& files, const core::Case& c) {
  if (files.empty()) throw MeshFamilyError("--reference-family: no study given");
  MeshFamily family;
  family.files = files;
  std::vector<std::vector<Eigen::MatrixXd>> levels;  // each mesh's samples [m], by nominal size
  for (std::size_t f = 0; f < files.size(); ++f) {
    const std::string& file = files[f];
    const auto fail = [&](const std::string& what) { throw MeshFamilyError(file + ": " + what); };
    std::ifstream in(file);
    if (!in) fail("cannot be read (a `tissue verify fem` fem.json was expected)");
    const json doc = json::parse(in, nullptr, false);
    if (doc.is_discarded()) fail("is not valid JSON");
    const json* study = nullptr;
    if (doc.contains("mesh_convergence") && doc["mesh_convergence"].contains(c.name))
      study = &doc["mesh_convergence"][c.name];
    if (!study) fail(fmt::format("/mesh_convergence/{}: a mesh study of case '{}' was expected", c.name, c.name));
    const std::string at = "/mesh_convergence/" + c.name;

    const std::string recorded = study->value("config", std::string());
    const std::string config = resolve_config(recorded);
    if (config.empty())
      fail(fmt::format("{}/config: the study's case file \"{}\" does not exist (nor under {}), so the problem it "
                       "solved cannot be checked",
                       at, recorded, TISSUE_SOURCE_DIR));
    const core::Case family_case = core::load_case(config);
    if (const std::string d = first_problem_difference(c.document, family_case.document); !d.empty())
      fail(fmt::format("its case {} differs from {} at {}: a study of the same problem was expected (they may differ "
                       "only in {})",
                       config, c.source_file, d, fmt::join(kDiscretisationKeys, ", ")));
    if (f == 0) {
      family.config = config;
      family.expected_order = expected_sample_order(family_case);
      const std::optional<Eigen::MatrixXd> points = rows_in_metres(study->value("sample_points_mm", json()));
      if (!points) fail(at + "/sample_points_mm: the samples' positions [mm] were expected");
      family.sample_points = *points;
    }

    if (!study->contains("levels") || !(*study)["levels"].is_array())
      fail(at + "/levels: the study's levels were expected");
    const json& study_levels = (*study)["levels"];
    for (std::size_t l = 0; l < study_levels.size(); ++l) {
      const json& level = study_levels[l];
      const std::string level_at = fmt::format("{}/levels/{}", at, l);
      if (level.contains("error"))
        fail(fmt::format("{}: the level at {} mm failed ({}); a family needs every mesh solved", level_at,
                         level.value("mesh_size_mm", 0.0), level["error"].dump()));
      // A level of `verify fem --meshes-per-level N` holds its meshes: each is averaged on its own.
      std::vector<json> meshes;
      if (level.contains("meshes"))
        for (const json& m : level["meshes"]) meshes.push_back(m);
      else
        meshes.push_back(level);
      for (const json& mesh : meshes) {
        const double size = mesh.value("mesh_size_mm", 0.0);
        const std::optional<Eigen::MatrixXd> u = rows_in_metres(mesh.value("sample_displacements_mm", json()));
        if (!(size > 0.0) || !u) fail(level_at + ": mesh_size_mm and sample_displacements_mm were expected");
        if (u->rows() != family.sample_points.rows())
          fail(fmt::format("{}: {} samples, where the family's first study has {}", level_at, u->rows(),
                           family.sample_points.rows()));
        if (f == 0 && &mesh == &meshes.front()) {
          const double nominal = level.value("mesh_size_mm", size);
          for (double h : family.h_mm)
            if (std::abs(nominal / h - 1.0) <= kFamilyLevelTolerance)
              fail(fmt::format("{}: levels {} and {} mm lie within {:.0f} % of each other; the first study gives the "
                               "family's levels (pass the study of the nominal sizes first, the meshes beside them "
                               "after it)",
                               level_at, h, nominal, 100 * kFamilyLevelTolerance));
          family.h_mm.push_back(nominal);
          levels.emplace_back();
        }
        // The nominal level nearest this mesh's size.
        std::size_t nearest = 0;
        for (std::size_t k = 1; k < family.h_mm.size(); ++k)
          if (std::abs(std::log(size / family.h_mm[k])) < std::abs(std::log(size / family.h_mm[nearest]))) nearest = k;
        if (std::abs(size / family.h_mm[nearest] - 1.0) > kFamilyLevelTolerance)
          fail(fmt::format("{}: a mesh of {} mm lies more than {:.0f} % from every level of {} ({} mm)", level_at, size,
                           100 * kFamilyLevelTolerance, files.front(), fmt::join(family.h_mm, ", ")));
        levels[nearest].push_back(*u);
      }
    }
  }
  for (const auto& level : levels) {
    Eigen::MatrixXd mean = Eigen::MatrixXd::Zero(family.sample_points.rows(), 3);
    for (const Eigen::MatrixXd& u : level) mean += u / static_cast<double>(level.size());
    family.means.push_back(mean);
    family.meshes.push_back(static_cast<int>(level.size()));
  }
  if (family.means.size() < 3)
    throw MeshFamilyError(fmt::format("{}: {} levels; an estimate needs three or more", files.front(),
                                      family.means.size()));
  family.estimate = estimate_remaining_error(family.means, family.h_mm, family.expected_order);
  if (!family.estimate.json.contains("estimated_error_of_finest_relative"))
    throw MeshFamilyError(fmt::format("{}: the family gives no estimate of its finest level's error ({})",
                                      files.front(), family.estimate.json.value("note", std::string())));
  return family;
}

void check_family_sample_points(const MeshFamily& family, const Eigen::MatrixXd& sample_points) {
  if (sample_points.rows() != family.sample_points.rows() ||
      (sample_points - family.sample_points).cwiseAbs().maxCoeff() > 1e-9)
    throw MeshFamilyError(fmt::format("{}: the family's samples do not lie at this run's sample points (to 1e-6 mm): "
                                      "a study of this case's /samples was expected",
                                      family.files.front()));
}

ReferenceErrorBar error_bar_against_family(const MeshFamily& family, const Eigen::MatrixXd& sample_points,
                                           const Eigen::MatrixXd& fem_samples) {
  check_family_sample_points(family, sample_points);
  const Eigen::MatrixXd& finest = family.means.back();
  const double finest_relative = family.estimate.json.at("estimated_error_of_finest_relative").get<double>();
  const double finest_error = finest_relative * finest.norm();
  const double to_finest = (fem_samples - finest).norm();
  const int meshes = family.meshes.back();
  const std::string finest_name = meshes > 1 ? fmt::format("{} mm, the mean of {} meshes", family.h_mm.back(), meshes)
                                             : fmt::format("{} mm", family.h_mm.back());
  const std::string finest_method =
      fmt::format("{}; the family's levels {} mm of {} meshes", estimate_method(family.estimate.json),
                  fmt::join(family.h_mm, " / "), fmt::join(family.meshes, " / "));

  ReferenceErrorBar bar;
  bar.known = true;
  bar.source = fmt::format("{}", fmt::join(family.files, ", "));
  bar.relative = (to_finest + finest_error) / fem_samples.norm();
  bar.method = fmt::format(
      "measured against the finest level of another mesh family of this problem ({}): {}, {:.2f} % of this "
      "reference; plus that level's own error ({:.2f} %: {})",
      family.config, finest_name, 100.0 * to_finest / fem_samples.norm(), 100.0 * finest_relative, finest_method);
  bar.rms_mm = bar.relative * fem_samples.norm() * 1e3 / std::sqrt(static_cast<double>(fem_samples.rows()));
  if (family.estimate.extrapolated.size() > 0) {
    bar.extrapolated_samples = family.estimate.extrapolated;
    bar.extrapolated_relative = finest_error / family.estimate.extrapolated.norm();
    bar.extrapolated_method = fmt::format("the samples extrapolated from the last two levels of another mesh family "
                                          "of this problem ({}); their bar is the estimated error of the finest level ({})",
                                          finest_method, finest_name);
  }
  return bar;
}

}  // namespace experiments
