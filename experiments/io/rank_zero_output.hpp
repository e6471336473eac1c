#pragma once
// The results folder of a command that runs under mpirun (`tissue solve fem|meshless`, `tissue verify fem`): rank 0
// stages it (core::OutputDirectory: nothing is left behind when the run fails) and writes the results files; every
// process learns the staging path, where each writes its own VTU pieces.
#include <memory>
#include <string>

#include "core/output_directory.hpp"

namespace experiments {

/// Rank 0 stages `out_dir` and returns it (null on the other processes); `staging`, when not null, receives the
/// staging folder's path on every process. A failure on rank 0 is thrown on every process, as std::runtime_error
/// naming the folder. Collective over MPI_COMM_WORLD.
std::unique_ptr<core::OutputDirectory> stage_on_rank_zero(const std::string& out_dir, std::string* staging = nullptr);

}  // namespace experiments
