#include "meshless/surrogate/surrogate_training.hpp"

#include <fmt/format.h>
#include <omp.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <fstream>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <thread>

#include "meshless/efg/efg_model.hpp"

namespace meshless {
namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// Resident memory of this process now [bytes] (/proc/self/statm), 0 when unavailable.
double resident_bytes() {
  std::ifstream statm("/proc/self/statm");
  long pages_total = 0, pages_resident = 0;
  if (!(statm >> pages_total >> pages_resident)) return 0.0;
  return static_cast<double>(pages_resident) * static_cast<double>(sysconf(_SC_PAGESIZE));
}

std::string describe(const SurfaceNodes& surface, const PatchLoad& load) {
  const Eigen::Vector3d x = surface.position.row(load.contact).transpose() * 1e3;
  return fmt::format("contact node ({:.4g}, {:.4g}, {:.4g}) mm, force ({:.4g}, {:.4g}, {:.4g}) N", x.x(),
                     x.y(), x.z(), load.force.x(), load.force.y(), load.force.z());
}

/// Solve one load on a set-up model: restart from rest under the patch traction, step to the response step.
SolvedLoad solve_one(EfgModel& model, const SurfaceNodes& surface, const QuadraturePoints& boundary,
                     const PatchLoad& load, const PatchSolveOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const Eigen::Vector3d x = surface.position.row(load.contact).transpose();
  const Eigen::Vector3d n = surface.normal.row(load.contact).transpose();
  SolvedLoad out;
  if (options.smooth_profile) {
    const double radius = smooth_profile_radius(options.patch_radius);
    const SmoothLoadPatch patch = smooth_load_patch(model.problem().mesh, boundary, x, n, radius);
    const Eigen::Vector3d scale = load.force / patch.profile_integral;  // the model's quadrature sums to force
    model.restart(patch.faces, [scale, x, radius](const Eigen::Vector3d& y) {
      return Eigen::Vector3d(scale * smooth_profile((y - x).norm(), radius));
    });
    out.patch_area = patch.profile_integral;
  } else {
    const LoadPatch patch = load_patch(model.problem().mesh, x, n, options.patch_radius);
    const Eigen::Vector3d traction = load.force / patch.area;  // uniform: total force / patch area
    model.restart(patch.faces, [traction](const Eigen::Vector3d&) { return traction; });
    out.patch_area = patch.area;
  }
  for (int step = 1; step <= options.response_step; ++step)
    out.newton_iterations += model.solve_step(step).newton_iterations;
  out.displacement = model.displacements_at(surface.position);  // eq. 7, not the nodal parameters
  out.seconds = seconds_since(t0);
  return out;
}

}  // namespace

int response_step(const EfgProblem& problem, bool at_end) {
  const int n = static_cast<int>(problem.step_times.size());
  if (n == 0) throw std::invalid_argument("response_step: the problem has no time steps");
  if (at_end) return n;
  for (int step = 1; step <= n; ++step)
    if (problem.load_scale(problem.step_times[step - 1]) >= 1.0 - 1e-12) return step;
  throw std::invalid_argument(
      fmt::format("the force is still ramping at the last step (t = {:g} s, {:.3g} of full load); expected "
                  "load.ramp_time <= "
                  "time.total for the end-of-ramp response",
                  problem.step_times.back(), problem.load_scale(problem.step_times.back())));
}

std::vector<SolvedLoad> solve_patch_loads(const EfgProblem& problem, const EfgOptions& efg_options,
                                          const SurfaceNodes& surface, const std::vector<PatchLoad>& loads,
                                          const PatchSolveOptions& options,
                                          const std::function<void(const std::string&)>& progress,
                                          PatchSolveReport* report) {
  const auto t_start = std::chrono::steady_clock::now();
  if (options.response_step < 1 || options.response_step > static_cast<int>(problem.step_times.size()))
    throw std::invalid_argument("solve_patch_loads: response_step outside the problem's steps");
  for (const PatchLoad& l : loads)
    if (l.contact < 0 || l.contact >= surface.size())
      throw std::invalid_argument("solve_patch_loads: a load's contact index is not a surface node");
  std::vector<SolvedLoad> results(loads.size());
  PatchSolveReport rep;
  if (loads.empty()) {
    if (report) *report = rep;
    return results;
  }
  std::mutex report_mutex;
  int done = 0;
  auto announce = [&](std::size_t i) {
    if (!progress) return;
    std::lock_guard<std::mutex> lock(report_mutex);
    ++done;
    const SolvedLoad& r = results[i];
    const Eigen::Vector3d u = r.displacement.row(loads[i].contact).transpose();
    progress(fmt::format(
        "solve {}/{}: {}: {} Newton iterations, |u| at the contact node {:.4g} mm ({:.1f} s)", done,
        loads.size(), describe(surface, loads[i]), r.newton_iterations, u.norm() * 1e3, r.seconds));
  };
  auto rethrow_with_context = [&](std::size_t i, const std::exception_ptr& e) {
    try {
      std::rethrow_exception(e);
    } catch (const std::exception& ex) {
      throw std::runtime_error(
          fmt::format("the full meshless model failed for {}: {}", describe(surface, loads[i]), ex.what()));
    }
  };

  // The model's own boundary quadrature, for the smooth profile's integral (read-only, shared by the workers).
  QuadraturePoints boundary;
  if (options.smooth_profile)
    boundary = boundary_quadrature(problem.mesh, problem.quadrature_order, problem.cut ? &*problem.cut : nullptr);

  // The first model and the first load, alone: its footprint decides how many models fit the budget.
  const double baseline = resident_bytes();
  auto t0 = std::chrono::steady_clock::now();
  auto first = std::make_unique<EfgModel>(problem, efg_options);
  first->setup_system();
  rep.setup_seconds = seconds_since(t0);
  try {
    results[0] = solve_one(*first, surface, boundary, loads[0], options);
  } catch (...) {
    rethrow_with_context(0, std::current_exception());
  }
  announce(0);
  rep.model_bytes = 1.25 * std::max(0.0, resident_bytes() - baseline);  // + transient solver work space
  const int hardware = std::max(1u, std::thread::hardware_concurrency());
  const int cap = options.max_workers > 0 ? options.max_workers : hardware;
  const int by_memory =
      rep.model_bytes > 0.0 ? static_cast<int>(options.memory_budget_bytes / rep.model_bytes) : cap;
  rep.workers = std::max(1, std::min({cap, by_memory, static_cast<int>(loads.size()) - 1}));
  // PETSc keeps process-wide state (its options stack, PETSC_COMM_WORLD), so its Krylov solve runs in one thread at
  // a time: a cloud too large to factorise trains its loads one after another.
  if (first->statistics().linear_solver_kind == LinearSolverKind::petsc_krylov) rep.workers = 1;
  const int threads_per_worker = std::max(1, hardware / rep.workers);

  std::atomic<std::size_t> next{1};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::size_t error_index = loads.size();
  std::mutex error_mutex;
  auto work = [&](int worker) {
    omp_set_num_threads(threads_per_worker);  // this thread's OpenMP loops (assembly, MLS) share the cores
    try {
      std::unique_ptr<EfgModel> own;
      EfgModel* model = first.get();
      if (worker > 0) {
        own = std::make_unique<EfgModel>(problem, efg_options);
        own->setup_system();
        model = own.get();
      }
      for (std::size_t i = next++; i < loads.size() && !failed; i = next++) {
        try {
          results[i] = solve_one(*model, surface, boundary, loads[i], options);
        } catch (...) {
          std::lock_guard<std::mutex> lock(error_mutex);
          if (i < error_index) {
            error_index = i;
            error = std::current_exception();
          }
          failed = true;
          return;
        }
        announce(i);
      }
    } catch (...) {  // a worker's own set-up failed
      std::lock_guard<std::mutex> lock(error_mutex);
      if (!error) error = std::current_exception();
      failed = true;
    }
  };
  if (rep.workers == 1) {
    work(0);
  } else {
    std::vector<std::thread> threads;
    for (int w = 0; w < rep.workers; ++w) threads.emplace_back(work, w);
    for (std::thread& t : threads) t.join();
  }
  if (error) {
    if (error_index < loads.size()) rethrow_with_context(error_index, error);
    std::rethrow_exception(error);
  }
  rep.wall_seconds = seconds_since(t_start);
  if (report) *report = rep;
  return results;
}

PatchComparison compare_load_patches(const EfgProblem& problem, const EfgOptions& efg_options,
                                     const SurfaceNodes& surface, const PatchLoad& load,
                                     const PatchSolveOptions& options) {
  EfgModel model(problem, efg_options);
  model.setup_system();
  PatchComparison out;
  const core::TetMesh& mesh = problem.mesh;
  std::vector<char> imprinted(mesh.boundary_faces.rows(), 0);
  for (std::size_t f = 0; f < mesh.face_tags.size(); ++f)
    if (mesh.face_tags[f] == core::FaceTag::load) {
      imprinted[f] = 1;
      ++out.imprinted_faces;
    }
  out.imprinted_area = mesh.tagged_area(core::FaceTag::load);
  if (out.imprinted_faces == 0)
    throw std::invalid_argument("compare_load_patches: the cloud has no load-tagged face");
  const Eigen::Vector3d traction = load.force / out.imprinted_area;
  model.restart(imprinted, [traction](const Eigen::Vector3d&) { return traction; });
  for (int step = 1; step <= options.response_step; ++step) model.solve_step(step);
  out.imprinted = model.displacements_at(surface.position);
  PatchSolveOptions uniform = options;  // the check compares the uniform training patch with the imprinted one
  uniform.smooth_profile = false;
  const SolvedLoad patch = solve_one(model, surface, QuadraturePoints{}, load, uniform);
  out.patch = patch.displacement;
  out.patch_area = patch.patch_area;
  const Eigen::Vector3d x = surface.position.row(load.contact).transpose();
  out.patch_faces =
      load_patch(mesh, x, surface.normal.row(load.contact).transpose(), options.patch_radius).num_faces;
  return out;
}

}  // namespace meshless
