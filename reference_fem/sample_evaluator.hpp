#pragma once
// Displacement at arbitrary material points (the case's sample points, paper §5.4) by finite-element
// interpolation. The points lie on the exact (curved) surface, so they may sit a hair outside the
// faceted mesh: such a point is projected into the nearest cell, within a stated tolerance.
#include <deal.II/dofs/dof_handler.h>
#include <deal.II/fe/mapping.h>
#include <deal.II/lac/vector.h>

#include <Eigen/Core>
#include <vector>

#include "core/ruled_surface.hpp"

namespace reference_fem {

class SampleEvaluator {
 public:
  /// Locate every point once (cell + reference coordinates, reusing the previous cell as a hint).
  /// @param points  #points by 3 [m]
  /// @param tolerance  largest distance [m] a point may lie outside the mesh; farther throws
  /// @param cut  when not null, a point behind the crack front is located on the lip core::RuledSurface::side
  ///             gives it (the rule the meshless model uses too): in a cell with no vertex on the other side
  SampleEvaluator(const dealii::Mapping<3>& mapping, const dealii::DoFHandler<3>& dof_handler,
                  const Eigen::MatrixXd& points, double tolerance, const core::RuledSurface* cut = nullptr);

  /// #points by 3 displacement [m] of the FE field `solution`.
  Eigen::MatrixXd evaluate(const dealii::Vector<double>& solution) const;

  /// Distance [m] from each point to where it is evaluated (0 for points inside the mesh).
  const std::vector<double>& offsets() const { return offsets_; }

 private:
  struct Location {
    typename dealii::DoFHandler<3>::active_cell_iterator cell;
    dealii::Point<3> unit_point;
  };
  const dealii::DoFHandler<3>& dof_handler_;
  std::vector<Location> locations_;
  std::vector<double> offsets_;
};

/// #vertices by 3 displacement [m] at the triangulation's vertices (index = deal.II vertex index, which
/// equals the core::TetMesh vertex index for meshes built by build_triangulation()).
Eigen::MatrixXd vertex_displacements(const dealii::DoFHandler<3>& dof_handler, const dealii::Vector<double>& solution);

}  // namespace reference_fem
