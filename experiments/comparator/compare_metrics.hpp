#pragma once
// What the comparator computes from sample displacements, free of any model: the eq. 34 RMSE, the flags of
// samples that are ill-posed for a point-wise comparison, and the FEM reference's own error bar from a mesh
// study. Units: inputs in metres (as core::Geometry and ModelResult hold them), outputs in mm where the name
// says so.
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/ruled_surface.hpp"

namespace experiments {

/// When a sample is flagged (docs/EXPERIMENTS.md, "Flagged samples").
struct SampleFlagRules {
  double patch_edge_distance = 0.0;  ///< [m] flag when |‖x − load centre‖ − load radius| < this
  double cut_distance = 0.0;         ///< [m] flag when the distance to the cut surface < this
};

/// Per sample: its distances to the load-patch edge and to the cut, and the flags they raise.
struct SampleDiagnostics {
  std::vector<double> edge_distance;                ///< [m] |‖x − load centre‖ − load radius|
  std::vector<std::optional<double>> cut_distance;  ///< [m]; empty when the case has no cut
  std::vector<bool> on_patch_edge;
  std::vector<bool> near_cut;
  bool flagged(std::size_t i) const { return on_patch_edge[i] || near_cut[i]; }
  std::size_t num_flagged() const;
  std::vector<bool> unflagged_mask() const;  ///< true for the samples kept in the "without flagged" RMSE
};

/// @param points  #samples by 3 [m]; the patch is the ball of `load_radius` around `load_centre`.
SampleDiagnostics diagnose_samples(const Eigen::MatrixXd& points, const Eigen::Vector3d& load_centre,
                                   double load_radius, const std::optional<core::RuledSurface>& cut,
                                   const SampleFlagRules& rules);

/// Eq. 34: sqrt(Σ_i ‖u_i − u_ref,i‖² / n) over the samples with include[i] (all when `include` is empty);
/// in the units of the inputs. NaN when no sample is included.
double rmse(const Eigen::MatrixXd& u, const Eigen::MatrixXd& u_reference, const std::vector<bool>& include = {});

/// Largest eq. 33 magnitude ‖u_i‖ over the samples.
double peak_magnitude(const Eigen::MatrixXd& u);

/// The reference's own discretisation error at the samples, as an RMS over the samples in mm (directly
/// comparable with an eq. 34 RMSE), when a mesh study of exactly this reference solve is known.
struct ReferenceErrorBar {
  bool known = false;
  double rms_mm = 0.0;       ///< estimated ‖U_h − U‖ / √n [mm]
  double relative = 0.0;     ///< the study's estimated ‖U_h − U‖ / ‖U_h‖ over all samples
  std::string method;        ///< how the study estimated it (Richardson order, or the first-order bound)
  std::string source;        ///< the study file
  std::string why_unknown;   ///< when !known: what is missing
  /// The study's extrapolated samples (#samples by 3 [m]) when it wrote them, and the error bar they carry: the
  /// finest level's estimated error, relative to the extrapolated samples' norm (extrapolating does not claim
  /// more accuracy than the finest level's estimate).
  std::optional<Eigen::MatrixXd> extrapolated_samples;
  double extrapolated_relative = 0.0;
  std::string extrapolated_method;
  /// The extrapolated samples' bar as an RMS over the samples [mm]: extrapolated_relative × ‖U*‖ / √n.
  /// Requires extrapolated_samples.
  double extrapolated_rms_mm() const;
  nlohmann::json to_json() const;
};

/// The rows of a `verify fem` sample array ([[x, y, z], ...], as written: sample_points_mm, sample_displacements_mm)
/// as a #rows by 3 matrix in the file's units; nullopt when it is not an array of three numbers per row.
std::optional<Eigen::MatrixXd> sample_rows(const nlohmann::json& rows);

/// How a study's estimate of its finest level's error was made (a `verify fem` "richardson" object): "Richardson
/// extrapolation over the study's last three levels (observed order p)", or the estimate's own note when its order
/// was outside the asymptotic range.
std::string estimate_method(const nlohmann::json& richardson);

/// Look the reference up in a `tissue verify fem` result (fem.json): the study of the case with this name
/// applies only when one of its solved levels has this mesh size and the same sample displacements as this run
/// (to a relative 1e-6), i.e. when the study solved exactly this reference. At the study's finest level the
/// error is the study's estimate; at a coarser level it is that level's distance to the finest plus the
/// finest's estimate (the triangle inequality: a bound, measured against a finer solve).
/// @param fem_samples  #samples by 3 [m], this run's FEM sample displacements
ReferenceErrorBar reference_error_bar(const nlohmann::json& verify_fem, const std::string& source,
                                      const std::string& case_name, double mesh_size,
                                      const Eigen::MatrixXd& fem_samples);

}  // namespace experiments
