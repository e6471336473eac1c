#include "experiments/io/rank_zero_output.hpp"

#include <deal.II/base/mpi.h>
#include <fmt/format.h>

#include <stdexcept>
#include <vector>

namespace experiments {

std::unique_ptr<core::OutputDirectory> stage_on_rank_zero(const std::string& out_dir, std::string* staging) {
  std::unique_ptr<core::OutputDirectory> out;
  std::string path, error;
  if (dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0) {
    try {
      out = std::make_unique<core::OutputDirectory>(out_dir);
      path = out->staging().string();
    } catch (const std::exception& e) {
      error = fmt::format("cannot create the output folder {}: {}", out_dir, e.what());
    }
  }
  const auto shared = dealii::Utilities::MPI::broadcast(MPI_COMM_WORLD, std::vector<std::string>{path, error}, 0);
  if (!shared[1].empty()) throw std::runtime_error(shared[1]);
  if (staging) *staging = shared[0];
  return out;
}

}  // namespace experiments
