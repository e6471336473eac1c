#include "reference_fem/amg_preconditioner.hpp"

#include <deal.II/base/mpi.h>
#include <deal.II/fe/fe_values.h>

#include <algorithm>
#include <vector>

namespace reference_fem {

using namespace dealii;

std::unique_ptr<Epetra_MultiVector> rigid_body_modes(const DoFHandler<3>& dof_handler, const Mapping<3>& mapping,
                                                     const IndexSet& locally_owned_dofs, const Epetra_Map& rows) {
  const MPI_Comm communicator = dof_handler.get_communicator();
  // Rotations about the body's centroid (of the cell centres), so the six modes are comparably scaled.
  Point<3> centre;
  double n_cells = 0.0;
  for (const auto& cell : dof_handler.active_cell_iterators())
    if (cell->is_locally_owned()) {
      centre += cell->center();
      n_cells += 1.0;
    }
  for (unsigned int d = 0; d < 3; ++d) centre[d] = Utilities::MPI::sum(centre[d], communicator);
  centre /= std::max(1.0, Utilities::MPI::sum(n_cells, communicator));

  auto result = std::make_unique<Epetra_MultiVector>(rows, 6);  // zero-initialised
  Epetra_MultiVector& modes = *result;
  const FiniteElement<3>& fe = dof_handler.get_fe();
  FEValues<3> fe_values(mapping, fe, Quadrature<3>(fe.get_unit_support_points()), update_quadrature_points);
  std::vector<types::global_dof_index> dofs(fe.n_dofs_per_cell());
  for (const auto& cell : dof_handler.active_cell_iterators()) {
    if (!cell->is_locally_owned()) continue;
    fe_values.reinit(cell);
    cell->get_dof_indices(dofs);
    for (unsigned int i = 0; i < dofs.size(); ++i) {
      if (!locally_owned_dofs.is_element(dofs[i])) continue;
      const int row = rows.LID(static_cast<int>(dofs[i]));
      const unsigned int c = fe.system_to_component_index(i).first;
      const Tensor<1, 3> x = fe_values.quadrature_point(i) - centre;
      modes[c][row] = 1.0;  // translation along e_c
      // Rotations u = w x x about e_z, e_x, e_y: (-y, x, 0), (0, -z, y), (z, 0, -x).
      if (c == 0) {
        modes[3][row] = -x[1];
        modes[5][row] = x[2];
      } else if (c == 1) {
        modes[3][row] = x[0];
        modes[4][row] = -x[2];
      } else {
        modes[4][row] = x[1];
        modes[5][row] = -x[0];
      }
    }
  }
  return result;
}

Teuchos::ParameterList ml_parameters(const TrilinosWrappers::SparseMatrix& matrix, const Epetra_MultiVector& modes,
                                     const AmgOptions& options) {
  TrilinosWrappers::PreconditionAMG::AdditionalData data;
  data.elliptic = true;  // smoothed aggregation with Chebyshev smoothing
  data.higher_order_elements = options.higher_order_elements;
  data.aggregation_threshold = options.aggregation_threshold;
  data.smoother_type = options.smoother_type;
  data.smoother_sweeps = options.smoother_sweeps;
  data.w_cycle = options.w_cycle;
  Teuchos::ParameterList list;
  std::unique_ptr<Epetra_MultiVector> unused_constant_modes;
  data.set_parameters(list, unused_constant_modes, matrix);
  list.set("PDE equations", 3);
  list.set("null space: type", "pre-computed");
  list.set("null space: dimension", options.rigid_body_modes ? 6 : 3);
  list.set("null space: vectors", const_cast<double*>(modes.Values()));  // ML copies them at set-up
  return list;
}

}  // namespace reference_fem
