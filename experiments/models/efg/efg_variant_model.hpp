#pragma once
// The paper's meshless model (the EFG of meshless/, paper §2) as models of the comparator, one per cut treatment:
// "enrichment", the proposed model (MLS weights enriched across the cut, eqs. 29-32), and "visibility", the baseline
// (the visibility criterion). Without a cut no weight is modified, so the two are one model: visibility says so
// (same_as) and the comparator solves once. "paper" is the proposed model in the paper's own configuration
// (/meshless/preset "paper", core::MeshlessSpec::in_paper_configuration), whatever the case's /meshless says about
// it, so that a table can show the published model beside this project's default.
#include "experiments/models/model.hpp"

namespace experiments {

class EfgVariantModel final : public Model {
 public:
  enum class Variant { enrichment, visibility, paper };
  explicit EfgVariantModel(Variant variant) : variant_(variant) {}

  std::string name() const override;
  std::string role() const override;
  std::string description() const override;
  bool needs_node_cloud() const override { return true; }
  std::string same_as(const core::Case& c) const override;
  int progress_lines(const core::Case& c) const override { return 1 + c.time.steps; }
  /// The case with /meshless/enrichment set to this variant (paper: "enrichment" in the paper's configuration),
  /// solved by solve_meshless (models/efg/meshless_runs.hpp).
  ModelResult solve(const core::Case& c, const core::Geometry& g, const SolveRequest& request) const override;
  /// Without a cut: one EfgModel set up on the cloud, restarted under each force (EfgModel::restart keeps the MLS
  /// tables and the pattern; each force factorises its own tangent, as the LRPIM's series does). A cut case sets up
  /// in each solve (the default).
  std::unique_ptr<LoadSeries> prepare_load_series(const core::Case& c, const core::Geometry& g) const override;

 private:
  /// The case this variant solves: /meshless/enrichment set to it (and the paper's configuration for "paper").
  core::Case variant_case(const core::Case& c) const;
  Variant variant_;
};

}  // namespace experiments
