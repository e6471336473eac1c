#include "reference_fem/distributed_triangulation.hpp"

#include <deal.II/base/mpi.h>
#include <deal.II/grid/grid_tools.h>
#include <deal.II/grid/tria_description.h>

#include <vector>

namespace reference_fem {

void distribute_triangulation(dealii::Triangulation<3>* whole,
                              dealii::parallel::fullydistributed::Triangulation<3>* distributed) {
  const MPI_Comm communicator = distributed->get_communicator();
  const unsigned int n_processes = dealii::Utilities::MPI::n_mpi_processes(communicator);
  std::vector<unsigned int> owner(whole->n_active_cells(), 0);
  if (n_processes > 1) {
    if (dealii::Utilities::MPI::this_mpi_process(communicator) == 0) {
      dealii::GridTools::partition_triangulation(n_processes, *whole, dealii::SparsityTools::Partitioner::metis);
      for (const auto& cell : whole->active_cell_iterators()) owner[cell->active_cell_index()] = cell->subdomain_id();
    }
    owner = dealii::Utilities::MPI::broadcast(communicator, owner, 0);
  }
  for (const auto& cell : whole->active_cell_iterators()) cell->set_subdomain_id(owner[cell->active_cell_index()]);
  const auto description =
      dealii::TriangulationDescription::Utilities::create_description_from_triangulation(*whole, communicator);
  distributed->create_triangulation(description);
}

}  // namespace reference_fem
