#pragma once
// The FEM reference's error bar measured against mesh studies of the same problem in another mesh family
// (`tissue compare --reference-family STUDY.json...`; docs/EXPERIMENTS.md, "The reference's error bar").
//
// Why: the shipped study (results/verify/fem.json) solves the reference's own mesh as its coarsest level, and the bar
// is that level's distance to the study's finest plus the finest level's estimated error (compare_metrics.hpp,
// reference_error_bar). When that study's observed order lies outside the asymptotic band, its estimate is not a
// Richardson one. Another family of meshes of the same continuum problem whose order lies inside the band can carry
// the estimate instead. Gmsh's levels are not nested, so each family level may be the mean of meshes solved a
// percent apart (studies run beside one another, `verify fem --sizes 12.12 11.88 ...`), which averages out the
// mesh-to-mesh noise (docs/FEM_REFERENCE.md, "Mesh-to-mesh noise"). The bound is the same triangle inequality:
// ‖U_h − U‖ ≤ ‖U_h − U_f‖ + ‖U_f − U‖, U_f the family's finest level.
//
// "The same problem": the family's case (the `config` its fem.json records) equals this case in everything but the
// discretisation (kDiscretisationKeys), and its samples lie at this case's sample points. Each refusal is a
// MeshFamilyError naming the file and what was expected; compare reads and checks the studies before any solve.
//
// Units: fem.json in mm; matrices here in metres. Plain functions and values; no shared state.
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/case.hpp"
#include "experiments/comparator/compare_metrics.hpp"
#include "experiments/comparator/mesh_study_estimate.hpp"

namespace experiments {

/// The case keys that choose the discretisation, not the problem: two cases that differ only here solve the same
/// continuum problem (the mesh family, the FEM's degree and solver, the meshless model's settings, what is written).
inline const std::vector<std::string> kDiscretisationKeys{"/description", "/geometry/mesh_size",
                                                          "/geometry/refinement", "/fem", "/meshless", "/compare",
                                                          "/surrogate", "/output"};

/// [-] How far a family level's mesh size may lie from the nominal size it is averaged into: meshes a percent or two
/// apart belong to one level, the next level (a ratio of 1.5) never does.
inline constexpr double kFamilyLevelTolerance = 0.05;

/// A refused family: what() is "FILE: <what was expected and what was found>" (with the JSON path where there is one).
class MeshFamilyError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The JSON pointer of the first difference between two case documents outside kDiscretisationKeys, or "" when
/// they state the same problem.
std::string first_problem_difference(const nlohmann::json& a, const nlohmann::json& b);

/// A mesh family of one problem, its levels averaged over the meshes beside each.
struct MeshFamily {
  std::vector<std::string> files;
  std::string config;                  ///< the family's case file, as resolved
  std::vector<double> h_mm;            ///< the nominal size of each level (the first file's), coarse to fine
  std::vector<int> meshes;             ///< meshes averaged at each level
  std::vector<Eigen::MatrixXd> means;  ///< each level's mean sample displacements, #samples by 3 [m]
  Eigen::MatrixXd sample_points;       ///< #samples by 3 [m], as the first file records them
  double expected_order = 0.0;         ///< expected_sample_order of the family's case
  MeshStudyEstimate estimate;          ///< over the means (estimate_remaining_error)
};

/// Reads `files` (fem.json of `tissue verify fem`) and checks them against case `c`: each holds a study of c.name
/// whose levels all solved, with the same number of samples; every study's config states c's problem
/// (first_problem_difference, the config read as recorded, or relative to the source tree when that path does not
/// exist); the first file's levels are the nominal sizes, every other file's level lies within kFamilyLevelTolerance
/// of one; three levels or more, and an estimate of the finest. Throws MeshFamilyError otherwise.
MeshFamily read_mesh_family(const std::vector<std::string>& files, const core::Case& c);

/// Throws MeshFamilyError when `sample_points` (this run's, #samples by 3 [m]) are not the family's, to 1e-6 mm.
void check_family_sample_points(const MeshFamily& family, const Eigen::MatrixXd& sample_points);

/// The bar of the solved reference `fem_samples` (#samples by 3 [m]) against `family`: its distance to the family's
/// finest level plus that level's estimated error, and the family's extrapolated samples with their bar (for
/// `--reference extrapolated`). Checks the sample points first (check_family_sample_points).
ReferenceErrorBar error_bar_against_family(const MeshFamily& family, const Eigen::MatrixXd& sample_points,
                                           const Eigen::MatrixXd& fem_samples);

}  // namespace experiments
