#pragma once
// The meshless model's own share of the uncertainty of Table 1's verdict: how far the proposed model's and
// the baseline's RMSEs against the same FEM reference move when only their node cloud changes. The difference
// of the two RMSEs is judged against this change and the reference's error bar combined (`tissue reproduce`).
//
// The input is the kept results of sweeps over the node cloud of a Table 1 case (for the cut case,
// configs/sweeps/cut_variants_*.json): each run folder's summary.json under <study>/runs/. A run counts only
// if it solved against the same reference as the Table 1 row (the same peak sample displacement, to 1e-9
// relative), so a study of another case or reference is never mixed in. The RMSEs are those against the solved
// reference, or those against the mesh study's extrapolated samples that compare writes beside them
// (summary.json `versus_extrapolated`), as the row's are.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace experiments {

/// The Table 1 row's own figures that the study's runs are set against [mm].
struct CloudChangeBaseline {
  std::string proposed;  ///< model name of the proposed model (e.g. "enrichment")
  std::string baseline;  ///< model name of the baseline (e.g. "visibility")
  double proposed_rmse_mm = 0.0;
  double baseline_rmse_mm = 0.0;
  double reference_peak_mm =
      0.0;  ///< the solved reference's peak sample displacement, which identifies the reference
  /// false: the RMSEs against the solved reference (summary.json `models`); true: against the extrapolated samples
  /// (`versus_extrapolated.models`), which a run written before compare wrote them lacks (it is then unused).
  bool versus_extrapolated = false;
  /// With versus_extrapolated: the bar of the row's extrapolated samples [mm] (summary.json
  /// `versus_extrapolated.error_bar_mm`), which identifies them; a run scored against other ones is unused.
  double extrapolated_bar_mm = 0.0;
};

struct CloudChange {
  bool known = false;
  /// The change used by the verdict [mm]: the largest change of the difference (proposed − baseline) over the
  /// runs that solved both models; when no run solved both, the largest change of one model's RMSE (an
  /// estimate only: the common part of the two models' change would cancel in the difference).
  double mm = 0.0;
  std::string measure;                            ///< "difference" or "one model's RMSE", as above
  std::string why_unknown;                        ///< when !known: no study, no usable run, ...
  nlohmann::json runs = nlohmann::json::array();  ///< per run: folder, nodes, each model's RMSE or why unused
  nlohmann::json to_json() const;
};

/// The cloud change of one Table 1 row from the given study folders (paths as given; a missing one is
/// reported in why_unknown or in `runs`, never an error: the Table still prints).
CloudChange cloud_change(const std::vector<std::string>& study_dirs, const CloudChangeBaseline& row);

}  // namespace experiments
