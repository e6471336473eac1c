#pragma once
// The undeformed body (u = 0 at every sample) as a model: a floor in every table. Its RMSE against the reference is
// the reference's own RMS sample displacement, so a model whose RMSE comes near it has learnt nothing about the
// deformation. It needs no mesh and takes no time.
#include "experiments/models/model.hpp"

namespace experiments {

class ZeroModel final : public Model {
 public:
  std::string name() const override { return "zero"; }
  std::string role() const override { return "floor: the undeformed body, u = 0"; }
  std::string description() const override { return "The undeformed body (u = 0), a floor every model must beat"; }
  int progress_lines(const core::Case&) const override { return 0; }
  ModelResult solve(const core::Case& c, const core::Geometry& g, const SolveRequest& request) const override;
};

}  // namespace experiments
