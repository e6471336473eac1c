// EFG model cost on box clouds of ~2k, 8k and 32k nodes (13^3, 20^3, 32^3; spacing 5 mm, d_max = 2, k = 6,
// quadrature order 2 on 6 tets per grid cell): one full assembly of eqs. 20-24 (material update, residual and
// tangent) and one elastic load step with each linear solver (docs/PERFORMANCE.md, docs/MESHLESS.md §2):
//  * BM_EfgSolve: the automatic choice (the direct solver, MUMPS, when its estimated LU fits the available memory, else the
//    PETSc Krylov solve);
//  * BM_EfgSolveKrylov / BM_EfgSolveMumps / BM_EfgSolveUmfpack / BM_EfgSolveJacobiBicgstab: each solver
//    forced, for the ratios within one run and the iterations against the cloud size;
//  * BM_EfgSolveMlGcr: the PETSc Krylov solve with the earlier default options (FGMRES, ML with GCR(20)/SOR level
//    smoothers, built from the tangent's sparser copy), against BM_EfgSolveKrylov's SSOR by Eisenstat's trick;
//  * BM_EfgDirectLung/mumps, /umfpack: one factorisation of configs/lung_small.json's tangent at its shipped
//    resolution (10 mm cloud) by each direct solver, in one run: the solver behind every lung solve; /mumps_blr_*: MUMPS's
//    block low-rank LU at dropping tolerances 1e-8, 1e-6 and 1e-4 (EfgOptions::direct_low_rank_tolerance), with the
//    relative residual of its solve (the exact LU's is round-off); /mumps_unknowns_graph: MUMPS ordering the graph of
//    the unknowns instead of the nodes' (EfgOptions::direct_node_ordering = false, as before); each with the
//    factorisation's operations (factorisation_Gflop);
//  * BM_EfgLungRunRefreshRule/2, /5: lung_small's whole run with EfgOptions::refactor_contraction 0.2 (before) and
//    0.5 (the default);
//  * BM_EfgPreconditioner: the preconditioners measured before choosing the default of EfgOptions::krylov_options
//    (2k nodes), and the symmetric option (VCI off, k = 0: CG against GMRES) and a smaller support (d_max 1.5);
//    all with PCML's own level smoother (one SSOR sweep); `ml` at 2k and 8k nodes is the earlier default;
//  * BM_EfgPreconditionerFromEnvironment: any PETSc options, from EFG_KRYLOV_OPTIONS, with the drop tolerance of the
//    preconditioner's matrix from EFG_DROP_TOLERANCE, the penalty factor from EFG_PENALTY_FACTOR and the box's
//    node numbering from EFG_NODE_ORDER (the surveys of docs/MESHLESS.md §2).
// Under `mpirun -np N` (scripts/run_benchmarks.sh with EFG_BENCH_PROCESSES=N) every process builds the model and
// the Krylov solves are distributed over them (meshless/solvers/petsc_krylov_solver.hpp); rank 0 reports, and
// BM_EfgSolveKrylovOneProcess gives the one-process figure of the same run.
// Cube clamped (penalty, eq. 23) on z = 0 and loaded by a shear traction on the top face; elastic step.
// Shape-function tabulation and sparsity are set-up work, timed separately in BM_EfgSetup.
#include <benchmark/benchmark.h>
#include <sys/resource.h>

#include <chrono>
#include <cstdlib>
#include <memory>
#include <string>
#include <tuple>

#include "benchmarks/mpi_benchmark_main.hpp"
#include "core/case.hpp"
#include "core/geometry.hpp"
#include "core/mesh_ordering.hpp"
#include "meshless/solvers/efg_linear_solver.hpp"
#include "meshless/efg/efg_model.hpp"
#include "meshless/verification/verification_problems.hpp"

namespace {

using meshless::LinearSolverKind;

/// Peak resident memory of this process so far [GB]. The sizes run in increasing order within each benchmark
/// family, so after a 32k benchmark this is the peak of the 32k model (set-up, assembly and the solve).
double peak_memory_gb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) * 1024.0 / 1e9;  // ru_maxrss is in KiB on Linux
}

/// A variant of the sheared box and of the solver options.
struct Variant {
  LinearSolverKind solver = LinearSolverKind::automatic;
  std::string krylov_options;  // empty: EfgOptions' default
  bool variationally_consistent = true;
  double d_max = 2.0;
  double penalty_factor = 1e3;
  double drop_tolerance = meshless::EfgOptions{}.preconditioner_drop_tolerance;
  bool node_order_for_locality = false;  // the box's nodes numbered as the geometry pipeline numbers a cloud (RCM)
  bool one_process = false;              // under mpirun: rank 0 solves alone (EfgOptions::distributed_krylov_solve)
  bool operator!=(const Variant& o) const {
    return std::tie(solver, krylov_options, variationally_consistent, d_max, penalty_factor, drop_tolerance,
                    node_order_for_locality, one_process) !=
           std::tie(o.solver, o.krylov_options, o.variationally_consistent, o.d_max, o.penalty_factor,
                    o.drop_tolerance, o.node_order_for_locality, o.one_process);
  }
};

/// The model shared by the benchmarks. main() destroys it before MPI and PETSc are finalised: its solver holds
/// PETSc objects.
std::unique_ptr<meshless::EfgModel>& cached_model() {
  static std::unique_ptr<meshless::EfgModel> model;
  return model;
}

/// One set-up model per size and variant, shared by the benchmarks (set-up of the 32k cloud takes tens of
/// seconds). Only one is kept alive at a time: the 32k model alone holds several GB.
meshless::EfgModel& model_for(int side, const Variant& variant = {}) {
  static int key_side = 0;
  static Variant key;
  std::unique_ptr<meshless::EfgModel>& model = cached_model();
  if (!model || key_side != side || key != variant) {
    model.reset();
    meshless::EfgOptions options;
    options.linear_solver = variant.solver;
    options.preconditioner_drop_tolerance = variant.drop_tolerance;
    options.distributed_krylov_solve = !variant.one_process;
    if (!variant.krylov_options.empty()) options.krylov_options = variant.krylov_options;
    meshless::EfgProblem problem = meshless::sheared_box_problem(side);
    problem.support.d_max = variant.d_max;
    problem.penalty_factor = variant.penalty_factor;
    problem.variationally_consistent = variant.variationally_consistent;
    if (variant.node_order_for_locality) core::order_for_locality(&problem.mesh);
    model = std::make_unique<meshless::EfgModel>(std::move(problem), options);
    model->setup_system();
    key_side = side;
    key = variant;
  }
  return *model;
}

/// The size of an assembly: nodes, matrix non-zeros, volume points, and the (point, node, node) triples whose
/// 3 by 3 products it sums (eq. 21), the work it does whatever the ordering.
void add_assembly_counters(benchmark::State& state, const meshless::EfgModel& model) {
  state.counters["nodes"] = model.statistics().num_nodes;
  state.counters["nnz"] = static_cast<double>(model.statistics().matrix_nonzeros);
  state.counters["nodes_per_point"] = model.statistics().mean_nodes_per_point;
  const meshless::ShapeTable& t = model.volume_points();
  double triples = 0;
  for (int q = 0; q < t.size(); ++q) triples += double(t.end(q) - t.begin(q)) * (t.end(q) - t.begin(q));
  state.counters["point_node_node_triples"] = triples;
  state.counters["points"] = t.size();
}

void BM_EfgSetup(benchmark::State& state) {
  const int side = static_cast<int>(state.range(0));
  for (auto _ : state) {
    meshless::EfgModel model(meshless::sheared_box_problem(side));
    model.setup_system();
    state.counters["shape_s"] = model.timings().shape_function_seconds;
  }
  state.counters["nodes"] = side * side * side;
}

void BM_EfgAssembly(benchmark::State& state) {
  meshless::EfgModel& model = model_for(static_cast<int>(state.range(0)));
  for (auto _ : state) model.assemble_system(true);
  add_assembly_counters(state, model);
  state.counters["peak_rss_GB"] = peak_memory_gb();
}

/// One elastic load step (meshless::EfgModel::solve_step): Newton with one linear solve and two assemblies;
/// the linear solve alone (factorisation or multigrid set-up included) is the `solve_s` counter.
void time_solve(benchmark::State& state, const Variant& variant) {
  meshless::EfgModel& model = model_for(static_cast<int>(state.range(0)), variant);
  meshless::StepRecord step;
  for (auto _ : state) step = model.solve_step(1);
  const meshless::EfgStatistics& st = model.statistics();
  state.counters["nodes"] = st.num_nodes;
  state.counters["solve_s"] = step.solve_seconds;
  state.counters["assembly_s"] = step.assembly_seconds;
  state.counters["newton_iterations"] = step.newton_iterations;
  state.counters["krylov_iterations"] = step.linear_iterations;
  state.counters["umfpack_peak_GB"] = st.direct_peak_memory_estimate / 1e9;
  state.counters["available_GB"] = st.available_memory / 1e9;
  state.counters["peak_rss_GB"] = peak_memory_gb();  // of rank 0's process so far, under mpirun
  state.counters["processes"] = variant.one_process ? 1 : meshless::petsc_processes();  // that the solve ran on
  state.SetLabel(st.linear_solver);
}

void BM_EfgSolve(benchmark::State& state) { time_solve(state, {}); }
void BM_EfgSolveKrylov(benchmark::State& state) { time_solve(state, {LinearSolverKind::petsc_krylov}); }
/// The same solve on rank 0 alone while the other processes wait: under `mpirun -np 2` the one-process figure of
/// the same run as BM_EfgSolveKrylov's distributed one. Registered after it, so that the others have nothing left
/// to do but wait in MPI_Finalize.
void BM_EfgSolveKrylovOneProcess(benchmark::State& state) {
  if (dealii::Utilities::MPI::this_mpi_process(MPI_COMM_WORLD) != 0) {
    state.SkipWithError("rank 0 runs this one alone");
    return;
  }
  Variant v{LinearSolverKind::petsc_krylov};
  v.one_process = true;
  time_solve(state, v);
}
/// The options EfgOptions::krylov_options had before SSOR by Eisenstat's trick: ML with GCR(20)/SOR level smoothers,
/// the hierarchy and the sweeps built from the tangent's sparser copy (drop tolerance 0.01), under FGMRES(200).
void BM_EfgSolveMlGcr(benchmark::State& state) {
  Variant v;
  v.solver = LinearSolverKind::petsc_krylov;
  v.krylov_options = meshless::kMlWithGcrSmoothersOptions;
  v.drop_tolerance = 0.01;
  time_solve(state, v);
}
void BM_EfgSolveMumps(benchmark::State& state) { time_solve(state, {LinearSolverKind::direct}); }
void BM_EfgSolveUmfpack(benchmark::State& state) { time_solve(state, {LinearSolverKind::direct_umfpack}); }

/// configs/lung_small.json's EFG problem at its shipped resolution (the case and its meshless geometry are built
/// once, untimed; Gmsh runs here).
meshless::EfgProblem lung_small_problem() {
  static const core::Case c = core::load_case(std::string(TISSUE_SOURCE_DIR) + "/configs/lung_small.json");
  static const core::Geometry g = [] {
    core::GeometryOptions options;
    options.build_fem_mesh = false;
    return core::build_geometry(c, options);
  }();
  return meshless::problem_from_case(c, g);
}

/// configs/lung_small.json's EFG model, set up and assembled once (main() destroys it before MPI is finalised).
std::unique_ptr<meshless::EfgModel>& lung_model() {
  static std::unique_ptr<meshless::EfgModel> model;
  return model;
}
meshless::EfgModel& assembled_lung_small() {
  std::unique_ptr<meshless::EfgModel>& model = lung_model();
  if (!model) {
    model = std::make_unique<meshless::EfgModel>(lung_small_problem());
    model->setup_system();
    model->assemble_system(true);  // the elastic tangent of the first step
  }
  return *model;
}

/// One factorisation (with its ordering) and one back-substitution of the lung tangent.
void BM_EfgDirectLung(benchmark::State& state, LinearSolverKind kind, double low_rank_tolerance,
                      bool node_ordering = true) {
  meshless::EfgModel& model = assembled_lung_small();
  meshless::EfgOptions options;
  options.linear_solver = kind;
  options.direct_low_rank_tolerance = low_rank_tolerance;
  options.direct_node_ordering = node_ordering;
  double flops = 0.0;
  double solve_seconds = 0.0, relative_residual = 0.0;
  std::string label;
  const Eigen::VectorXd rhs = Eigen::VectorXd::Ones(model.system_matrix().rows());
  for (auto _ : state) {
    meshless::EfgLinearSolver solver(options, model.sparsity(), model.nodes(), "lung_small");
    solver.prepare(model.system_matrix());
    const auto t0 = std::chrono::steady_clock::now();
    const Eigen::VectorXd x = solver.solve(rhs);
    solve_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    relative_residual = (model.system_matrix() * x - rhs).norm() / rhs.norm();
    label = solver.description();
    flops = solver.factorisation_flops();
  }
  state.counters["factorisation_Gflop"] = flops / 1e9;
  state.counters["relative_residual"] = relative_residual;
  state.counters["nodes"] = model.statistics().num_nodes;
  state.counters["nnz"] = static_cast<double>(model.statistics().matrix_nonzeros);
  state.counters["back_substitution_s"] = solve_seconds;
  state.counters["peak_rss_GB"] = peak_memory_gb();
  state.SetLabel(label);
}
/// One assembly of configs/lung_small.json's EFG model at its shipped resolution: the material update and the
/// residual, with the tangent (range 1) or without it (range 0). The cost of every Newton iteration of a lung run.
void BM_EfgAssemblyLung(benchmark::State& state) {
  meshless::EfgModel& model = assembled_lung_small();
  const bool with_matrix = state.range(0) != 0;
  for (auto _ : state) model.assemble_system(with_matrix);
  add_assembly_counters(state, model);
}
/// configs/lung_small.json's whole EFG run (10 steps, k = 1) with the kept factors refreshed when an iteration
/// contracts the residual by less than 1 / (range / 10) (EfgOptions::refactor_contraction = range / 10): the
/// tangent-reuse rule, measured where it matters. Set-up excluded; assembly, solve and Newton iterations counted.
void BM_EfgLungRunRefreshRule(benchmark::State& state) {
  meshless::EfgOptions options;
  options.refactor_contraction = static_cast<double>(state.range(0)) / 10.0;
  meshless::EfgTimings timings;
  int newton = 0, factorisations = 0;
  double peak = 0.0;
  for (auto _ : state) {
    state.PauseTiming();
    meshless::EfgModel model(lung_small_problem(), options);
    model.setup_system();
    state.ResumeTiming();
    newton = factorisations = 0;
    for (int step = 1; step <= static_cast<int>(model.problem().step_times.size()); ++step) {
      const meshless::StepRecord r = model.solve_step(step);
      newton += r.newton_iterations;
      factorisations += r.factorisations;
    }
    timings = model.timings();
    peak = model.nodal_displacements().rowwise().norm().maxCoeff();
  }
  state.counters["assembly_s"] = timings.assembly_seconds;
  state.counters["solve_s"] = timings.solve_seconds;
  state.counters["newton_iterations"] = newton;
  state.counters["factorisations"] = factorisations;
  state.counters["max_nodal_u_mm"] = 1e3 * peak;
}
void BM_EfgSolveJacobiBicgstab(benchmark::State& state) { time_solve(state, {LinearSolverKind::jacobi_bicgstab}); }

void BM_EfgPreconditioner(benchmark::State& state, const std::string& options, bool vci, double d_max,
                          double penalty_factor = 1e3) {
  time_solve(state, {LinearSolverKind::petsc_krylov, options, vci, d_max, penalty_factor});
}

/// Any PETSc options string, from the environment variable EFG_KRYLOV_OPTIONS, the drop tolerance of the
/// preconditioner's matrix from EFG_DROP_TOLERANCE and the clamp's penalty factor from EFG_PENALTY_FACTOR (a survey of
/// one's own options; reports an error when the options are unset).
void BM_EfgPreconditionerFromEnvironment(benchmark::State& state) {
  const char* options = std::getenv("EFG_KRYLOV_OPTIONS");
  if (!options || !*options) {
    state.SkipWithError("set EFG_KRYLOV_OPTIONS to the PETSc options to measure");
    return;
  }
  Variant variant{LinearSolverKind::petsc_krylov, options, true, 2.0};
  // The preconditioner's matrix: the tangent itself by default; EFG_DROP_TOLERANCE=0.01 gives the sparser copy.
  if (const char* drop = std::getenv("EFG_DROP_TOLERANCE"); drop && *drop) variant.drop_tolerance = std::stod(drop);
  // The penalty factor of the clamp (eq. 23; 1000 by default), which sets much of the iteration count.
  if (const char* penalty = std::getenv("EFG_PENALTY_FACTOR"); penalty && *penalty)
    variant.penalty_factor = std::stod(penalty);
  // EFG_NODE_ORDER=rcm: the box numbered by reverse Cuthill-McKee, as core::build_geometry numbers a lung's cloud
  // (core/mesh_ordering.hpp), instead of layer by layer from the clamp.
  if (const char* order = std::getenv("EFG_NODE_ORDER"); order && std::string(order) == "rcm")
    variant.node_order_for_locality = true;
  time_solve(state, variant);
}

const std::string kGmres = "-ksp_type gmres -ksp_gmres_restart 200 -ksp_pc_side right ";

}  // namespace

BENCHMARK(BM_EfgSetup)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_EfgAssembly)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kSecond)->Iterations(2);
// All solvers at each size (ratios within one run). The 32k cloud does not fit UMFPACK, so its automatic
// choice (BM_EfgSolve/32) is the PETSc Krylov solve.
BENCHMARK(BM_EfgSolve)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_EfgSolveKrylov)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_EfgSolveMlGcr)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_EfgSolveMumps)->Arg(13)->Arg(20)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_EfgSolveUmfpack)->Arg(13)->Arg(20)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_EfgDirectLung, mumps, LinearSolverKind::direct, 0.0)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_EfgDirectLung, mumps_unknowns_graph, LinearSolverKind::direct, 0.0, false)
    ->Unit(benchmark::kSecond)
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_EfgDirectLung, mumps_blr_1e-8, LinearSolverKind::direct, 1e-8)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_EfgDirectLung, mumps_blr_1e-6, LinearSolverKind::direct, 1e-6)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_EfgDirectLung, mumps_blr_1e-4, LinearSolverKind::direct, 1e-4)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_EfgDirectLung, umfpack, LinearSolverKind::direct_umfpack, 0.0)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_EfgAssemblyLung)->Arg(1)->Arg(0)->Unit(benchmark::kSecond)->Iterations(3);
BENCHMARK(BM_EfgLungRunRefreshRule)->Arg(2)->Arg(5)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_EfgSolveJacobiBicgstab)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kSecond)->Iterations(1);

// The preconditioner survey on the 2k-node cloud (right-preconditioned GMRES(200) unless stated).
BENCHMARK_CAPTURE(BM_EfgPreconditioner, gamg, kGmres + "-pc_type gamg -pc_gamg_square_graph 0 -pc_gamg_threshold 0.05", true, 2.0)
    ->Arg(13)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_EfgPreconditioner, hypre_boomeramg,
                  kGmres + "-pc_type hypre -pc_hypre_boomeramg_strong_threshold 0.5 -pc_hypre_boomeramg_coarsen_type HMIS "
                           "-pc_hypre_boomeramg_interp_type ext+i -pc_hypre_boomeramg_P_max 4 "
                           "-pc_hypre_boomeramg_nodal_coarsen 6 -pc_hypre_boomeramg_vec_interp_variant 2",
                  true, 2.0)
    ->Arg(13)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_EfgPreconditioner, ml, kGmres + "-pc_type ml", true, 2.0)->Arg(13)->Arg(20)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_EfgPreconditioner, ssor, kGmres + "-pc_type sor", true, 2.0)->Arg(13)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_EfgPreconditioner, bicgstab_ml, "-ksp_type bcgs -pc_type ml", true, 2.0)
    ->Arg(13)->Unit(benchmark::kSecond)->Iterations(1);
// Symmetric tangent (plain eq. 22 without VCI, k = 0): CG against GMRES with the same preconditioner.
BENCHMARK_CAPTURE(BM_EfgPreconditioner, symmetric_gmres_ml, kGmres + "-pc_type ml", false, 2.0)
    ->Arg(13)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_EfgPreconditioner, symmetric_cg_ml, "-ksp_type cg -pc_type ml", false, 2.0)
    ->Arg(13)->Unit(benchmark::kSecond)->Iterations(1);
// What sets the iteration count (docs/MESHLESS.md §2): the penalty (factor 10 instead of 1000) and the support
// size (d_max 1.5 instead of 2).
BENCHMARK_CAPTURE(BM_EfgPreconditioner, penalty_10_ml, kGmres + "-pc_type ml", true, 2.0, 10.0)
    ->Arg(13)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_EfgPreconditioner, dmax_1_5_ml, kGmres + "-pc_type ml", true, 1.5)
    ->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kSecond)->Iterations(1);

// EFG_KRYLOV_OPTIONS='...' BENCH_FILTER='BM_EfgPreconditionerFromEnvironment/13/' scripts/run_benchmarks.sh bench_efg
BENCHMARK(BM_EfgPreconditionerFromEnvironment)->Arg(10)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kSecond)->Iterations(1);
// Last, so that under mpirun the processes other than rank 0 have finished everything else (see above):
// EFG_BENCH_PROCESSES=2 BENCH_FILTER='BM_EfgSolveKrylov(OneProcess)?/(13|20|32)/' scripts/run_benchmarks.sh bench_efg
BENCHMARK(BM_EfgSolveKrylovOneProcess)->Arg(13)->Arg(20)->Arg(32)->Unit(benchmark::kSecond)->Iterations(1);

int main(int argc, char** argv) {
  return bench::run_benchmarks_with_petsc(argc, argv, [] {
    cached_model().reset();
    lung_model().reset();
  });
}
