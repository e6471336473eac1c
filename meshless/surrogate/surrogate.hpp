#pragma once
// The fitted force -> displacement surrogate (paper §3) and its real-time query: a force vector at a contact
// point gives the displacement of the contact node (eqs. 25-27) and of every surface node (eq. 28), the three
// force components superposed as in the paper. docs/SURROGATE.md describes the model, its limits and its
// accuracy.
//
// Lifetime and threads: a Surrogate is immutable after construction; query() is const, allocates nothing and
// may run from several threads at once, each with its own output buffer. Units: SI (m, N) in and out.
#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/tet_mesh.hpp"
#include "meshless/surrogate/contact_region.hpp"
#include "meshless/surrogate/region_field.hpp"
#include "meshless/surrogate/surrogate_fit.hpp"

namespace meshless {

/// Everything a surrogate file holds (meshless/surrogate/surrogate_file.hpp).
struct SurrogateData {
  std::string case_name;
  std::string case_hash;               ///< surrogate_case_hash() of the case it was trained on
  double max_force = 0.0;              ///< [N] every component was trained over [-max_force, max_force]
  std::vector<double> levels;          ///< trained signed levels [N]
  double patch_radius = 0.0;           ///< [m] traction patch of the training loads
  std::string patch_profile = "uniform";  ///< its traction: "uniform" or "smooth" (surrogate_load_patch.hpp)
  std::string response_time;           ///< "end_of_ramp" or "end"
  double response_seconds = 0.0;       ///< the simulated time at which displacements were recorded [s]
  std::vector<int> surface_vertex;     ///< #S node ids in the case's meshless node cloud
  core::PointMatrix surface_position;  ///< #S by 3 [m]
  std::vector<ContactFit> contacts;    ///< contact indices refer to the surface nodes above
  /// Set: every contact above is a trained contact of this region, and a query inside it answers with
  /// region_field (eq. 28 with the contact position as a variable, region_field.hpp) and eqs. 25-27 interpolated
  /// between the contacts (contact_region.hpp); unset: a query takes the nearest trained contact.
  std::optional<ContactRegion> region;
  std::optional<RegionField> region_field;  ///< set exactly when region is
  nlohmann::json report;  ///< training figures, held-out errors, timings (for people, not queries)
};

/// The answer to one query (the surface displacements go to the caller's buffer).
struct SurrogateResponse {
  int contact = -1;  ///< the nearest trained contact (index into SurrogateData::contacts)
  /// The surface node (row of the surface buffer) of the answer: the trained contact's node, or inside a contact
  /// region the surface node nearest the query point.
  int contact_node = -1;
  double contact_distance = 0.0;    ///< [m] from the query point to contact_node
  /// Inside a contact region, or within the contact tolerance of a trained contact node: the answer is trained.
  bool on_trained_contact = false;
  bool in_contact_region = false;  ///< the region's interpolation answered (false without a region)
  Eigen::Vector3d force =
      Eigen::Vector3d::Zero();  ///< [N] the force evaluated (clamped to the trained range)
  bool force_in_range = true;  ///< false: a component exceeded max_force and was clamped (never extrapolated)
  Eigen::Vector3d contact_displacement = Eigen::Vector3d::Zero();  ///< [m] eqs. 25-27, superposed
  double max_surface_displacement = 0.0;                           ///< [m] largest |u| over the surface nodes
  int max_surface_node = -1;
};

class Surrogate {
 public:
  /// Precomputes every surface node's force polynomials from the eq. 28 functions (so a query is one small
  /// matrix-vector product per call). `contact_tolerance` [m]: a query point farther than this from every
  /// trained contact node is flagged (on_trained_contact = false); <= 0 means the patch radius.
  explicit Surrogate(SurrogateData data, double contact_tolerance = 0.0);

  const SurrogateData& data() const { return data_; }
  int num_surface_nodes() const { return static_cast<int>(data_.surface_position.rows()); }
  int num_contacts() const { return static_cast<int>(data_.contacts.size()); }
  double contact_tolerance() const { return tolerance_; }

  /// Inside the contact region (if any) the trained contacts are interpolated and the dent transported to the
  /// query point (contact_region.hpp); elsewhere the NEAREST trained contact node answers, flagged when farther
  /// than the contact tolerance (docs/SURROGATE.md §4). A force component outside [-max_force, max_force] is
  /// clamped and flagged.
  /// @param point contact point [m]
  /// @param force [N]
  /// @param surface #S by 3 buffer, resized only when its size is wrong; receives u at every surface node [m]
  SurrogateResponse query(const Eigen::Vector3d& point, const Eigen::Vector3d& force,
                          core::PointMatrix* surface) const;

 private:
  /// The contact region's answer at `point` (inside it), into r and u.
  void interpolate_in_region(const Eigen::Vector3d& point, SurrogateResponse* r, core::PointMatrix* surface) const;

  SurrogateData data_;
  double tolerance_ = 0.0;
  std::vector<Eigen::MatrixXd>
      nodal_;  ///< per contact: 3S by sum_j lambda_j, columns sigma_x^1.., sigma_y^1..
  // With a contact region: eqs. 25-27 interpolated, eq. 28 as one field of the position plus the interpolated
  // corrections that make it each trained contact's own fit at that contact.
  std::optional<ContactInterpolation> interpolation_;
  std::optional<RegionFieldEvaluator> region_field_;
  /// Per trained contact: its own eq. 28 (nodal_) minus the region's field at its node, 3S by the region's force
  /// columns (sigma_j^m, m = 1..lambda'_j of the region).
  std::vector<Eigen::MatrixXd> correction_;
};

}  // namespace meshless
