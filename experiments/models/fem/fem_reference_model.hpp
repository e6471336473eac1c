#pragma once
// The FEM reference (reference_fem/, deal.II P2 on the case's FEM mesh) as a model of the comparator: the "fem" of
// /compare/reference, and fem_model_result, which turns any FEM run (`tissue solve fem` under mpirun too) into the
// model-neutral ModelResult.
#include "experiments/models/model.hpp"
#include "reference_fem/fem_model.hpp"

namespace experiments {

class FemReferenceModel final : public Model {
 public:
  std::string name() const override { return "fem"; }
  std::string role() const override { return "reference"; }
  std::string description() const override {
    return "The finite-element reference: deal.II P2 tetrahedra, Newton, AMG (docs/FEM_REFERENCE.md)";
  }
  bool needs_fem_mesh() const override { return true; }
  /// Solves on this process alone (MPI_COMM_SELF): the comparator runs as one process.
  ModelResult solve(const core::Case& c, const core::Geometry& g, const SolveRequest& request) const override;
};

/// The FEM reference's run of case `c` as a ModelResult; `geometry_seconds` (building the geometry and the FEM
/// mesh) is added to the set-up and total times and recorded in the details.
ModelResult fem_model_result(const core::Case& c, const core::Geometry& geometry,
                             const reference_fem::FemRunResult& run, double geometry_seconds);

}  // namespace experiments
