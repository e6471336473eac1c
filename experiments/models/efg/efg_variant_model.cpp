#include "experiments/models/efg/efg_variant_model.hpp"

#include "experiments/models/efg/meshless_runs.hpp"

namespace experiments {

std::string EfgVariantModel::name() const {
  switch (variant_) {
    case Variant::enrichment: return "enrichment";
    case Variant::visibility: return "visibility";
    case Variant::paper: return "paper";
  }
  return {};
}

std::string EfgVariantModel::role() const {
  switch (variant_) {
    case Variant::enrichment: return "proposed: the EFG with MLS weights enriched across the cut (eqs. 29-32)";
    case Variant::visibility: return "baseline: the EFG with the visibility criterion across the cut";
    case Variant::paper:
      return "as published: the proposed EFG in the paper's configuration (plain Gauss quadrature of eq. 22, the "
             "enrichment without a front transition)";
  }
  return {};
}

std::string EfgVariantModel::description() const {
  switch (variant_) {
    case Variant::enrichment: return "The paper's EFG model, enrichment across the cut (docs/MESHLESS.md)";
    case Variant::visibility: return "The paper's EFG model, visibility criterion across the cut (the baseline)";
    case Variant::paper: return "The paper's EFG model as published: /meshless/preset \"paper\" (docs/MESHLESS.md §1)";
  }
  return {};
}

std::string EfgVariantModel::same_as(const core::Case& c) const {
  if (variant_ == Variant::visibility && !c.cut) return "enrichment";
  // A case already in the paper's configuration makes its proposed model the published one.
  if (variant_ == Variant::paper && c.meshless.preset == core::MeshlessSpec::Preset::paper) return "enrichment";
  return {};
}

ModelResult EfgVariantModel::solve(const core::Case& c, const core::Geometry& g, const SolveRequest& request) const {
  core::Case variant_case = c;
  if (variant_ == Variant::paper) variant_case.meshless = c.meshless.in_paper_configuration();
  variant_case.meshless.enrichment = variant_ == Variant::visibility ? "visibility" : "enrichment";
  ModelResult r = solve_meshless(variant_case, g, request.vtu_prefix, [&](const std::string& line) {
    if (request.on_step) request.on_step(name() + ": " + line);
  });
  r.model = "meshless (" + name() + ")";
  return r;
}

}  // namespace experiments
