// tissue: the command-line front end of the harness (see README.md and docs/ARCHITECTURE.md).
#include <CLI/CLI.hpp>
#include <deal.II/base/mpi.h>
#include <deal.II/base/multithread_info.h>
#include <omp.h>
#include <fmt/format.h>

#include <cstring>
#include <iostream>

#include "core/case_error.hpp"
#include "core/mpi_session_directory.hpp"
#include "core/openblas_kernel.hpp"
#include "experiments/commands/case_commands.hpp"
#include "experiments/commands/fit_commands.hpp"
#include "experiments/commands/probe_commands.hpp"
#include "experiments/commands/compare_command.hpp"
#include "experiments/commands/export_command.hpp"
#include "experiments/io/progress.hpp"
#include "experiments/commands/reproduce_command.hpp"
#include "experiments/commands/rsr_command.hpp"
#include "experiments/commands/solve_commands.hpp"
#include "experiments/commands/sweep_command.hpp"
#include "experiments/commands/verify_commands.hpp"

int main(int argc, char** argv) {
  // First, before any thread or MPI: OpenBLAS's kernels for this CPU, which may run this program again.
  core::use_supported_openblas_kernel(argv);
  // Then, for a process not started by mpirun, its own Open MPI session directory, removed after MPI_Finalize: two
  // `tissue` commands started side by side would otherwise race on the shared one (core/mpi_session_directory.hpp).
  const core::SingletonMpiSessionDirectory session_directory;
  // MPI and PETSc, finalised when main returns: for the distributed FEM reference and the EFG model's PETSc Krylov
  // solve (docs/MESHLESS.md §2); one thread per core of the node, shared among the processes on it. Only
  // `solve fem`, `solve meshless` and `verify fem` are distributed: other commands would run N copies side by side.
  dealii::Utilities::MPI::MPI_InitFinalize mpi(argc, argv);
  const bool root = dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) == 0;
  if (dealii::Utilities::MPI::n_mpi_processes(MPI_COMM_WORLD) > 1) {
    const bool distributed =
        argc > 2 && ((std::strcmp(argv[1], "solve") == 0 &&
                      (std::strcmp(argv[2], "fem") == 0 || std::strcmp(argv[2], "meshless") == 0)) ||
                     (std::strcmp(argv[1], "verify") == 0 && std::strcmp(argv[2], "fem") == 0));
    if (!distributed) {
      if (root)
        std::cerr << "error: only `tissue solve fem`, `tissue solve meshless` and `tissue verify fem` run under mpirun "
                     "with more than one process\n";
      return 2;
    }
    // The EFG model's OpenMP loops (assembly, shape functions) get this process's share of the cores too.
    omp_set_num_threads(static_cast<int>(dealii::MultithreadInfo::n_threads()));
  }
  CLI::App app{"tissue — accuracy and speed of a meshless soft-tissue cutting model against a FEM reference"};
  app.require_subcommand(1);
  const std::string blas = core::openblas_core_name();
  app.set_version_flag("--version", "tissue 0.1.0 (BLAS: " +
                                        (blas.empty() ? std::string("not OpenBLAS") : "OpenBLAS, " + blas + " kernels") +
                                        ")");
  experiments::add_case_commands(app);
  experiments::add_solve_commands(app);
  experiments::add_verify_commands(app);
  experiments::add_fit_commands(app);
  experiments::add_probe_commands(app);
  experiments::add_compare_command(app);
  experiments::add_export_commands(app);
  experiments::add_sweep_command(app);
  experiments::add_rsr_command(app);
  experiments::add_reproduce_command(app);
  // Set after the subcommands, which would otherwise inherit it: each states its own detail in its own footer.
  app.footer("`tissue SUBCOMMAND --help` describes a subcommand: its options, what it computes and what it writes.");
  try {
    app.parse(argc, argv);
  } catch (const experiments::CommandResult& r) {
    return r.exit_code;
  } catch (const CLI::ParseError& e) {  // --help and usage errors: print once
    return root ? app.exit(e) : e.get_exit_code();
  } catch (const core::CaseError& e) {  // found alike by every MPI process: rank 0 reports it
    if (root) std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << (root ? std::string() : fmt::format("[rank {}] ", dealii::Utilities::MPI::this_mpi_process(
                                                                       MPI_COMM_WORLD)))
              << "error: " << e.what() << "\n";
    return 1;
  } catch (const std::string& e) {  // the Gmsh SDK throws its last error as a string
    std::cerr << "error: " << e << "\n";
    return 1;
  }
  return 0;
}
