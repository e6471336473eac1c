#pragma once
// Displacement at arbitrary material points (the case's sample points, paper §5.4) by finite-element
// interpolation. The points lie on the exact (curved) surface, so they may sit a hair outside the
// faceted mesh: such a point is projected into the nearest cell, within a stated tolerance.
//
// Distributed runs locate every point on the whole serial mesh (the one the distributed triangulation was
// cut from, so one process count or another finds the same cell), then each point is evaluated by the
// process that owns its cell and the values are summed over the processes.
#include <deal.II/grid/cell_id.h>
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/fe/mapping.h>
#include <deal.II/lac/trilinos_vector.h>

#include <Eigen/Core>
#include <vector>

#include "core/ruled_surface.hpp"
#include "core/tet_mesh.hpp"

namespace reference_fem {

class SampleEvaluator {
 public:
  /// Locate every point once (cell + reference coordinates, reusing the previous cell as a hint) on
  /// `whole_mesh`, a serial triangulation with the same coarse cells as the dof_handler's (the serial mesh a
  /// distributed triangulation was built from, or the dof_handler's own triangulation when it is serial).
  /// @param points  #points by 3 [m]
  /// @param tolerance  largest distance [m] a point may lie outside the mesh; farther throws
  /// @param cut  when not null, a point behind the crack front is located on the lip core::RuledSurface::side
  ///             gives it (the rule the meshless model uses too): in a cell with no vertex on the other side
  SampleEvaluator(const dealii::Mapping<3>& mapping, const dealii::Triangulation<3>& whole_mesh,
                  const dealii::DoFHandler<3>& dof_handler, const Eigen::MatrixXd& points, double tolerance,
                  const core::RuledSurface* cut = nullptr);

  /// #points by 3 displacement [m] of the FE field `solution` (with ghost entries), on every process.
  /// Collective over the solution's communicator.
  Eigen::MatrixXd evaluate(const dealii::TrilinosWrappers::MPI::Vector& solution) const;

  /// Distance [m] from each point to where it is evaluated (0 for points inside the mesh).
  const std::vector<double>& offsets() const { return offsets_; }

 private:
  struct Location {
    dealii::CellId cell_id;  // on the whole mesh
    dealii::Point<3> unit_point;
    /// The cell on this process when it owns it (else an invalid iterator: another process evaluates).
    typename dealii::DoFHandler<3>::active_cell_iterator cell;
  };
  const dealii::DoFHandler<3>& dof_handler_;
  std::vector<Location> locations_;
  std::vector<double> offsets_;
};

/// #vertices by 3 displacement [m] at the vertices of `mesh`, on every process, for a dof_handler on a
/// triangulation built from `mesh` by build_triangulation() (and possibly distributed: coarse cell id = tet
/// index). Collective over the solution's communicator.
Eigen::MatrixXd vertex_displacements(const dealii::DoFHandler<3>& dof_handler,
                                     const dealii::TrilinosWrappers::MPI::Vector& solution, const core::TetMesh& mesh);

}  // namespace reference_fem
