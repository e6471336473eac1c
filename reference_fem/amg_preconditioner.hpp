#pragma once
// Algebraic multigrid for the elasticity tangent: Trilinos ML smoothed aggregation (through deal.II's
// TrilinosWrappers::PreconditionAMG) with the six rigid-body modes as its near null space. deal.II 9.4 has no
// helper for the rigid-body modes (DoFTools::extract_rigid_body_modes came later), so they are computed here
// from the DoF support points. Why ML and these settings: docs/FEM_REFERENCE.md ("The linear solver").
#include <deal.II/base/index_set.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/fe/mapping.h>
#include <deal.II/lac/trilinos_precondition.h>
#include <deal.II/lac/trilinos_sparse_matrix.h>

#include <Epetra_MultiVector.h>
#include <Teuchos_ParameterList.hpp>

#include <memory>

namespace reference_fem {

/// The ML settings that matter for P1/P2 elasticity tangents (the rest are deal.II's defaults).
struct AmgOptions {
  bool higher_order_elements = true;   ///< P2: aggregate on the matrix graph of all nodes (edge nodes too)
  double aggregation_threshold = 1e-4; ///< drop weak couplings below this when aggregating
  const char* smoother_type = "Chebyshev";
  unsigned int smoother_sweeps = 2;    ///< Chebyshev degree, or sweeps of the other smoothers
  bool w_cycle = false;
  bool rigid_body_modes = true;        ///< false: the three translations only (what extract_constant_modes gives)
};

/// The six rigid-body modes of a 3-component displacement field (translations along x, y, z; rotations about
/// z, x, y through the centroid of the cell centres) at the support points of the locally owned DoFs, in
/// `rows` (the matrix's row partition). Collective.
std::unique_ptr<Epetra_MultiVector> rigid_body_modes(const dealii::DoFHandler<3>& dof_handler,
                                                     const dealii::Mapping<3>& mapping,
                                                     const dealii::IndexSet& locally_owned_dofs,
                                                     const Epetra_Map& rows);

/// The ML parameter list of smoothed aggregation on `matrix`: elliptic settings with Chebyshev smoothing,
/// aggregates of whole nodes (3 DoFs, which deal.II numbers consecutively) and the first 3 (translations) or
/// all 6 columns of `modes` as the near null space. `modes` must outlive the preconditioner's set-up.
Teuchos::ParameterList ml_parameters(const dealii::TrilinosWrappers::SparseMatrix& matrix,
                                     const Epetra_MultiVector& modes, const AmgOptions& options = {});

}  // namespace reference_fem
