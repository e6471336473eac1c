#include "reference_fem/verification.hpp"

#include <deal.II/base/function.h>
#include <deal.II/base/quadrature_lib.h>
#include <deal.II/grid/grid_generator.h>
#include <deal.II/grid/tria.h>
#include <deal.II/numerics/vector_tools.h>

#include <chrono>
#include <cmath>

#include "core/convergence_rate.hpp"
#include "core/timoshenko_cantilever.hpp"
#include "reference_fem/sample_evaluator.hpp"
#include "reference_fem/viscoelastic_solver.hpp"

namespace reference_fem {
namespace {

using namespace dealii;

// GridGenerator colorize ids of a box: x=0 -> 0, x=L -> 1, y=0 -> 2, y=W -> 3, z=0 -> 4, z=W -> 5.
constexpr unsigned int kXMin = 0, kXMax = 1, kYMin = 2, kZMin = 4;

/// deal.II 9.4 cannot colorize simplex boxes, so set the ids from the face centres.
void colorize_box(Triangulation<3>* tria, const Point<3>& lo, const Point<3>& hi) {
  const double tol = 1e-8 * lo.distance(hi);
  for (const auto& cell : tria->active_cell_iterators())
    for (const auto f : cell->face_indices()) {
      if (!cell->face(f)->at_boundary()) continue;
      const Point<3> c = cell->face(f)->center();
      for (unsigned int d = 0; d < 3; ++d) {
        if (std::abs(c[d] - lo[d]) < tol) cell->face(f)->set_boundary_id(2 * d);
        if (std::abs(c[d] - hi[d]) < tol) cell->face(f)->set_boundary_id(2 * d + 1);
      }
    }
}

void make_box(Triangulation<3>* tria, const std::vector<unsigned int>& n, const Point<3>& lo, const Point<3>& hi) {
  GridGenerator::subdivided_hyper_rectangle_with_simplices(*tria, n, lo, hi);
  colorize_box(tria, lo, hi);
}

void make_bar(Triangulation<3>* tria) {
  // A 2 x 1 x 1 split of a 2 x 1 x 1 bar: uniform fields are exact on any mesh, so a coarse one suffices.
  make_box(tria, {2, 1, 1}, Point<3>(0, 0, 0), Point<3>(2, 1, 1));
}

BoundaryConditions roller_planes() {
  BoundaryConditions bc;
  const unsigned int ids[3] = {kXMin, kYMin, kZMin};
  for (int c = 0; c < 3; ++c) {
    DirichletCondition d;
    d.boundary_id = ids[c];
    d.components = {{c == 0, c == 1, c == 2}};
    bc.dirichlet.push_back(d);
  }
  return bc;
}

std::vector<double> step_times(const UniaxialOptions& o) {
  std::vector<double> times{0.0};  // the instantaneous load step (dt = 0, phi = 1)
  for (int n = 1; n <= o.steps; ++n) times.push_back(o.end_time * n / o.steps);
  return times;
}

/// support_stiffness > 0: the x = 0 face is held by that elastic support, and its displacement is checked too.
UniaxialResult run_uniaxial(const UniaxialOptions& o, const BoundaryConditions& bc, bool creep, double load,
                            double support_stiffness = 0.0) {
  Triangulation<3> tria;
  make_bar(&tria);
  SolverParameters parameters;
  parameters.material = o.material;
  parameters.degree = o.degree;
  parameters.newton.tolerance = 1e-12;
  ViscoelasticSolver solver(tria, parameters, bc);
  solver.setup_system();
  const auto& m = o.material;
  const double tau = m.relaxation_time();
  UniaxialResult result;
  solver.run(step_times(o), [&](const StepReport& report) {
    UniaxialSample s;
    s.time = report.time;
    if (creep) {
      s.computed = solver.average_strain()(0);
      s.exact = load / m.K1 + load / m.K2 * (1.0 - std::exp(-m.K2 * s.time / m.eta));
    } else {
      s.computed = solver.average_stress()(0);
      s.exact = load * m.K1 / (m.K1 + m.K2) * (m.K2 + m.K1 * std::exp(-s.time / tau));
    }
    result.max_relative_error = std::max(result.max_relative_error, std::abs(s.computed - s.exact) / std::abs(s.exact));
    result.max_newton_iterations = std::max(result.max_newton_iterations, report.newton_iterations);
    result.history.push_back(s);
    if (support_stiffness > 0.0) {
      Vector<double> u(3);
      VectorTools::point_value(solver.mapping(), solver.dof_handler(), solver.solution(), Point<3>(0.0, 0.5, 0.5), u);
      const double exact = load / support_stiffness;
      result.max_support_relative_error =
          std::max(result.max_support_relative_error, std::abs(u(0) - exact) / exact);
    }
  });
  result.final_ball_strain = solver.strain_in_ball(Eigen::Vector3d(1.0, 0.5, 0.5), 0.4);
  return result;
}

/// The Timoshenko & Goodier cantilever (nu = 0 here); I = B D^3 / 12 so that the end shear integrates to P over the
/// B x D section.
using Timoshenko = core::TimoshenkoCantilever;

class ExactField : public Function<3> {
 public:
  explicit ExactField(const Timoshenko& t) : Function<3>(3), t_(t) {}
  double value(const Point<3>& p, const unsigned int c) const override {
    return t_.displacement(Eigen::Vector3d(p[0], p[1], p[2]))(c);
  }

 private:
  Timoshenko t_;
};

}  // namespace

UniaxialResult run_uniaxial_relaxation(const UniaxialOptions& options, double eps0) {
  BoundaryConditions bc = roller_planes();
  DirichletCondition pull;
  pull.boundary_id = kXMax;
  pull.components = {{true, false, false}};
  pull.value = Eigen::Vector3d(eps0 * 2.0, 0, 0);  // bar length 2
  bc.dirichlet.push_back(pull);
  return run_uniaxial(options, bc, false, eps0);
}

UniaxialResult run_uniaxial_creep(const UniaxialOptions& options, double sigma0) {
  BoundaryConditions bc = roller_planes();
  TractionCondition t;
  t.boundary_id = kXMax;
  t.traction = Eigen::Vector3d(sigma0, 0, 0);
  bc.tractions.push_back(t);
  return run_uniaxial(options, bc, true, sigma0);
}

UniaxialResult run_uniaxial_creep_on_elastic_support(const UniaxialOptions& options, double sigma0,
                                                     double support_stiffness) {
  BoundaryConditions bc = roller_planes();
  bc.dirichlet.erase(bc.dirichlet.begin());  // the x = 0 roller gives way to the spring
  ElasticSupportCondition spring;
  spring.boundary_id = kXMin;
  spring.stiffness = [support_stiffness](const Eigen::Vector3d&) { return support_stiffness; };
  bc.supports.push_back(spring);
  TractionCondition t;
  t.boundary_id = kXMax;
  t.traction = Eigen::Vector3d(sigma0, 0, 0);
  bc.tractions.push_back(t);
  return run_uniaxial(options, bc, true, sigma0, support_stiffness);
}

CantileverLevel run_cantilever(const CantileverOptions& o, int subdivisions) {
  const auto start = std::chrono::steady_clock::now();
  Triangulation<3> tria;
  const unsigned int n = static_cast<unsigned int>(subdivisions);
  make_box(&tria, {5 * n, n, n}, Point<3>(0, -o.depth / 2, 0), Point<3>(o.length, o.depth / 2, o.width));
  const Timoshenko exact{o.force, o.youngs_modulus, 0.0, o.length, o.depth, o.width * std::pow(o.depth, 3) / 12.0};

  BoundaryConditions bc;
  DirichletCondition clamp;
  clamp.boundary_id = kXMin;
  clamp.field = [exact](const Eigen::Vector3d& x, double) { return exact.displacement(x); };
  bc.dirichlet.push_back(clamp);
  TractionCondition shear;
  shear.boundary_id = kXMax;
  shear.field = [exact](const Eigen::Vector3d& x, double) { return exact.end_traction(x); };
  bc.tractions.push_back(shear);

  SolverParameters parameters;
  parameters.material.K1 = o.youngs_modulus;
  parameters.material.K2 = o.youngs_modulus;  // irrelevant in a dt = 0 step
  parameters.material.eta = 1.0;
  parameters.material.nu = 0.0;
  parameters.material.k = 0.0;
  parameters.degree = o.degree;
  parameters.newton.tolerance = 1e-10;
  ViscoelasticSolver solver(tria, parameters, bc);
  solver.setup_system();
  const StepReport report = solver.do_time_step(0.0);  // instantaneous step: modulus K1

  CantileverLevel level;
  level.subdivisions = subdivisions;
  level.h = o.depth / subdivisions;
  level.n_dofs = solver.dof_handler().n_dofs();
  level.newton_iterations = report.newton_iterations;
  const QGaussSimplex<3> quadrature(static_cast<unsigned int>(o.degree + 2));
  Vector<float> cell_errors(tria.n_active_cells());
  VectorTools::integrate_difference(solver.mapping(), solver.dof_handler(), solver.solution(), ExactField(exact),
                                    cell_errors, quadrature, VectorTools::L2_norm);
  const double error = VectorTools::compute_global_error(tria, cell_errors, VectorTools::L2_norm);
  Vector<double> zero(solver.dof_handler().n_dofs());
  VectorTools::integrate_difference(solver.mapping(), solver.dof_handler(), zero, ExactField(exact), cell_errors,
                                    quadrature, VectorTools::L2_norm);
  level.l2_error = error / VectorTools::compute_global_error(tria, cell_errors, VectorTools::L2_norm);

  Eigen::MatrixXd tip(1, 3);
  tip << o.length, 0.0, o.width / 2;
  const SampleEvaluator evaluator(solver.mapping(), tria, solver.dof_handler(), tip, 1e-9);
  level.tip_deflection = evaluator.evaluate(solver.solution())(0, 1);
  level.exact_tip_deflection = exact.displacement(tip.row(0).transpose())(1);
  level.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return level;
}

double convergence_rate(const std::vector<CantileverLevel>& levels) {
  std::vector<double> h, error;
  for (const auto& l : levels) {
    h.push_back(l.h);
    error.push_back(l.l2_error);
  }
  return core::convergence_rate(h, error);
}

}  // namespace reference_fem
