// tissue: the command-line front end of the harness (see README.md and docs/ARCHITECTURE.md).
#include <CLI/CLI.hpp>
#include <deal.II/base/mpi.h>
#include <fmt/format.h>

#include <iostream>

#include "core/case_error.hpp"
#include "experiments/case_commands.hpp"
#include "experiments/fit_commands.hpp"
#include "experiments/probe_commands.hpp"
#include "experiments/compare_command.hpp"
#include "experiments/progress.hpp"
#include "experiments/rsr_command.hpp"
#include "experiments/solve_commands.hpp"
#include "experiments/sweep_command.hpp"
#include "experiments/verify_commands.hpp"

int main(int argc, char** argv) {
  // MPI and PETSc (the EFG model's AMG-Krylov solve, docs/MESHLESS.md §2), finalised when main returns.
  dealii::Utilities::MPI::MPI_InitFinalize mpi_initialization(argc, argv);
  CLI::App app{"tissue — accuracy and speed of a meshless soft-tissue cutting model against a FEM reference"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "tissue 0.1.0");
  experiments::add_case_commands(app);
  experiments::add_solve_commands(app);
  experiments::add_verify_commands(app);
  experiments::add_fit_commands(app);
  experiments::add_probe_commands(app);
  experiments::add_compare_command(app);
  experiments::add_sweep_command(app);
  experiments::add_rsr_command(app);
  try {
    app.parse(argc, argv);
  } catch (const experiments::CommandResult& r) {
    return r.exit_code;
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const core::CaseError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  } catch (const std::string& e) {  // the Gmsh SDK throws its last error as a string
    std::cerr << "error: " << e << "\n";
    return 1;
  }
  return 0;
}
