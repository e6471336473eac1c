#pragma once
// The LRPIM model (meshless/lrpim/, Liu & Gu's local radial point interpolation as Zhou et al., the paper's ref. [32],
// use it for soft tissue) as a model of the comparator: the model the paper's Fig. 9 times the proposed one against.
// It reads only the node cloud's nodes and boundary triangles (no background cells) and has no treatment of a cut,
// so it refuses cut cases (cannot_solve), and the comparator reports it as not solved there.
#include "experiments/models/model.hpp"

namespace experiments {

class LrpimCaseModel final : public Model {
 public:
  std::string name() const override { return "lrpim"; }
  std::string role() const override {
    return "Fig. 9 baseline: LRPIM, local radial point interpolation (Liu & Gu; Zhou et al., the paper's ref. [32])";
  }
  std::string description() const override {
    return "The LRPIM meshless model of the paper's Fig. 9 (MQ RBF + linear basis, MLPG; docs/LRPIM.md)";
  }
  bool needs_node_cloud() const override { return true; }
  std::string cannot_solve(const core::Case& c) const override;
  ModelResult solve(const core::Case& c, const core::Geometry& g, const SolveRequest& request) const override;
  /// Sets up once (the local quadrature and the RPIM tabulation: most of a small case's solve) and restarts the
  /// model under each force (meshless::lrpim::LrpimModel::restart).
  std::unique_ptr<LoadSeries> prepare_load_series(const core::Case& c, const core::Geometry& g) const override;
};

/// `tissue verify lrpim`: the RPIM invariants, the patch tests, the cantilever rates and the creep bars at k = 0 and
/// k = 2 (meshless::lrpim::run_lrpim_verification) into OUT/lrpim.json and OUT/lrpim.md; exit 1 when one fails.
int run_verify_lrpim(const std::string& out_dir, bool quick);

}  // namespace experiments
