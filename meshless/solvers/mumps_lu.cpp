#include "meshless/solvers/mumps_lu.hpp"

#include <algorithm>

#include <dmumps_c.h>
#include <fmt/format.h>
#include <mpi.h>

#include <cstring>
#include <mutex>
#include <stdexcept>
#include <vector>

namespace meshless {

namespace {

// MUMPS's control and information arrays are documented 1-based (ICNTL(7), INFOG(1), ...); the C structure
// holds them 0-based.
MUMPS_INT& icntl(DMUMPS_STRUC_C& id, int i) { return id.icntl[i - 1]; }
MUMPS_INT infog(const DMUMPS_STRUC_C& id, int i) { return id.infog[i - 1]; }
double& cntl(DMUMPS_STRUC_C& id, int i) { return id.cntl[i - 1]; }

constexpr MUMPS_INT kJobInit = -1, kJobEnd = -2, kJobAnalyse = 1, kJobFactorise = 2, kJobSolve = 3;
constexpr MUMPS_INT kOrderingMetis = 5;  // ICNTL(7)
constexpr int kMaxWorkspaceRetries = 4;

/// MUMPS keeps Fortran module state during a call (its load balancing's allocations), so two instances called
/// at once from two threads corrupt each other (the surrogate's parallel training did: "PB allocation in
/// DMUMPS_LOAD_INIT", then a crash). Every call of every instance takes this lock.
std::mutex& mumps_call_lock() {
  static std::mutex lock;
  return lock;
}

/// INFOG(1) codes that mean the workspace estimated by the analysis was too small (MUMPS user guide §8): the
/// factorisation is retried with a larger relaxation, ICNTL(14).
bool workspace_too_small(MUMPS_INT code) {
  return code == -8 || code == -9 || code == -14 || code == -15 || code == -17 || code == -20;
}

std::string describe(const DMUMPS_STRUC_C& id) {
  const MUMPS_INT code = infog(id, 1), detail = infog(id, 2);
  switch (code) {
    case -6: return fmt::format("the matrix is structurally singular (structural rank {})", detail);
    case -10: return "the matrix is numerically singular";
    case -5:
    case -7:
    case -13:
      return fmt::format("out of memory (MUMPS error {}, allocation of {} {})", code, detail < 0 ? -detail : detail,
                         detail < 0 ? "million entries" : "entries");
    default:
      if (workspace_too_small(code))
        return fmt::format("MUMPS's workspace stayed too small (error {}) after raising its relaxation to {} %", code,
                           id.icntl[13]);
      return fmt::format("MUMPS error INFOG(1) = {}, INFOG(2) = {}", code, detail);
  }
}

}  // namespace

struct MumpsLu::Mumps {
  DMUMPS_STRUC_C id;
  bool initialised = false, analysed = false;
  std::vector<MUMPS_INT> rows, columns;  // 1-based coordinates of the analysed pattern
  std::vector<double> values;            // in the coordinates' order
  std::vector<double> rhs;

  ~Mumps() {
    int finalized = 0;
    MPI_Finalized(&finalized);
    if (!initialised || finalized) return;  // MUMPS may not be called after MPI_Finalize: leak rather than abort
    run(kJobEnd);
  }
  void run(MUMPS_INT job) {
    const std::lock_guard<std::mutex> hold(mumps_call_lock());
    id.job = job;
    dmumps_c(&id);
  }
};

MumpsLu::MumpsLu(std::string name, double low_rank_tolerance, bool symmetric_part, int block_size)
    : mumps_(std::make_unique<Mumps>()), name_(std::move(name)), symmetric_part_(symmetric_part),
      block_size_(block_size) {
  if (!(low_rank_tolerance >= 0.0))
    throw std::invalid_argument(
        fmt::format("MumpsLu '{}': the low-rank tolerance must be >= 0 (0: exact LU), got {}", name_, low_rank_tolerance));
  if (block_size < 1)
    throw std::invalid_argument(
        fmt::format("MumpsLu '{}': the block size must be >= 1 (1: no blocks), got {}", name_, block_size));
  int mpi_initialised = 0, mpi_finalized = 0;
  MPI_Initialized(&mpi_initialised);
  MPI_Finalized(&mpi_finalized);
  if (!mpi_initialised || mpi_finalized)
    throw std::logic_error(fmt::format(
        "EfgModel '{}': the direct solver (MUMPS) needs MPI, which is not initialised in this program (construct "
        "dealii::Utilities::MPI::MPI_InitFinalize at the start of main)",
        name_));
  DMUMPS_STRUC_C& id = mumps_->id;
  std::memset(&id, 0, sizeof id);
  id.comm_fortran = static_cast<MUMPS_INT>(MPI_Comm_c2f(MPI_COMM_SELF));
  id.par = 1;  // the host process works too (there is only one)
  // Unsymmetric: the VCI tangent and the k != 0 tangent are not symmetric (docs/MESHLESS.md §2). Or LDL^T with
  // pivoting (general symmetric, SYM = 2) of the symmetric part, about half the work.
  id.sym = symmetric_part ? 2 : 0;
  mumps_->run(kJobInit);
  if (infog(id, 1) < 0)
    throw std::runtime_error(fmt::format("EfgModel '{}': MUMPS could not start: {}", name_, describe(id)));
  mumps_->initialised = true;
  icntl(id, 1) = -1;  // no error, diagnostic, statistics or warning output: failures are thrown with their cause
  icntl(id, 2) = -1;
  icntl(id, 3) = -1;
  icntl(id, 4) = 0;
  icntl(id, 7) = kOrderingMetis;  // nested dissection: the point of using MUMPS here (header)
  // The graph of the blocks (the nodes) rather than of the unknowns: a better nested dissection, and a cheaper one.
  if (block_size > 1) icntl(id, 15) = -block_size;
  // Null-pivot detection: without it MUMPS factorises a singular matrix without a word (a body without enough
  // clamped surface, a node that no point supports). A pivot is null below 1e-5 eps ||A|| (CNTL(3) = 0).
  icntl(id, 24) = 1;
  if (low_rank_tolerance > 0.0) {
    icntl(id, 35) = 2;  // BLR in the factorisation and the solve (MUMPS 5.5 user guide, ICNTL(35))
    cntl(id, 7) = low_rank_tolerance;
  }
}

MumpsLu::~MumpsLu() = default;

void MumpsLu::factorise(const SparseMatrix& a) {
  Mumps& m = *mumps_;
  DMUMPS_STRUC_C& id = m.id;
  if (a.rows() != a.cols())
    throw std::invalid_argument(fmt::format("MumpsLu::factorise: expected a square matrix, got {} x {}", a.rows(),
                                            a.cols()));
  if (a.rows() % block_size_ != 0)
    throw std::invalid_argument(fmt::format("MumpsLu '{}': the matrix order {} is not a multiple of the block size {}",
                                            name_, a.rows(), block_size_));
  const bool first = !m.analysed;
  if (first) {
    m.rows.clear();
    m.columns.clear();
    m.rows.reserve(static_cast<std::size_t>(a.nonZeros()));
    m.columns.reserve(static_cast<std::size_t>(a.nonZeros()));
  } else if (a.rows() != id.n ||
             a.nonZeros() != (symmetric_part_ ? analysed_entries_ : static_cast<Eigen::Index>(m.rows.size()))) {
    throw std::invalid_argument(fmt::format(
        "MumpsLu::factorise: the pattern changed ({} x {} with {} entries; analysed {} x {} with {}): make a new "
        "solver for a new pattern",
        a.rows(), a.cols(), a.nonZeros(), id.n, id.n, m.rows.size()));
  }
  // A cut body's matrix keeps spare room per row (uncompressed); walk the entries in use.
  if (symmetric_part_) {
    fill_symmetric_part(a, first);
  } else {
    m.values.resize(static_cast<std::size_t>(a.nonZeros()));
    std::size_t e = 0;
    for (Eigen::Index i = 0; i < a.outerSize(); ++i)
      for (SparseMatrix::InnerIterator it(a, i); it; ++it, ++e) {
        if (first) {
          m.rows.push_back(static_cast<MUMPS_INT>(i + 1));
          m.columns.push_back(static_cast<MUMPS_INT>(it.index() + 1));
        }
        m.values[e] = it.value();
      }
  }
  id.n = static_cast<MUMPS_INT>(a.rows());
  id.nnz = static_cast<MUMPS_INT8>(m.values.size());
  id.irn = m.rows.data();
  id.jcn = m.columns.data();
  id.a = m.values.data();
  if (first) {
    m.run(kJobAnalyse);
    if (infog(id, 1) < 0)
      throw std::runtime_error(fmt::format("EfgModel '{}': sparse LU analysis failed: {}", name_, describe(id)));
    m.analysed = true;
  }
  for (int attempt = 0;; ++attempt) {
    m.run(kJobFactorise);
    if (!workspace_too_small(infog(id, 1)) || attempt == kMaxWorkspaceRetries) break;
    icntl(id, 14) = 2 * std::max<MUMPS_INT>(icntl(id, 14), 20);
  }
  if (infog(id, 1) < 0)
    throw std::runtime_error(fmt::format("EfgModel '{}': sparse LU factorisation failed: {}", name_, describe(id)));
  if (infog(id, 28) > 0)
    throw std::runtime_error(fmt::format(
        "EfgModel '{}': sparse LU factorisation failed: the matrix is numerically singular ({} null pivots of {})",
        name_, infog(id, 28), id.n));
  // INFOG(29) counts entries, or millions of entries when negative (it would overflow).
  factor_entries_ = infog(id, 29) >= 0 ? static_cast<double>(infog(id, 29)) : -1e6 * infog(id, 29);
  factorisation_flops_ = id.rinfog[2];
}

void MumpsLu::fill_symmetric_part(const SparseMatrix& a, bool first) {
  Mumps& m = *mumps_;
  // Walked afresh on every call: a matrix with spare room per row (a cut body's) may hold its entries elsewhere
  // in its arrays from one factorisation to the next; the order of the entries in use is the analysed one.
  m.values.clear();
  const int* outer = a.outerIndexPtr();
  const int* inner = a.innerIndexPtr();
  const double* value = a.valuePtr();
  const int* lengths = a.innerNonZeroPtr();  // null when compressed
  auto end_of = [&](Eigen::Index i) { return lengths ? outer[i] + lengths[i] : outer[i + 1]; };
  for (Eigen::Index i = 0; i < a.outerSize(); ++i)
    for (Eigen::Index e = outer[i]; e < end_of(i); ++e) {
      const Eigen::Index j = inner[e];
      const int* begin = inner + outer[j];
      const int* last = inner + end_of(j);
      const int* found = std::lower_bound(begin, last, static_cast<int>(i));
      if (found == last || *found != i)
        throw std::invalid_argument(fmt::format(
            "MumpsLu '{}': the symmetric part needs a structurally symmetric pattern; ({}, {}) has no ({}, {})", name_,
            i, j, j, i));
      if (j < i) continue;  // the upper triangle and the diagonal: MUMPS sums a symmetric matrix's given entries
      m.values.push_back(0.5 * (value[e] + value[found - inner]));
      if (first) {
        m.rows.push_back(static_cast<MUMPS_INT>(i + 1));
        m.columns.push_back(static_cast<MUMPS_INT>(j + 1));
      }
    }
  if (first) analysed_entries_ = a.nonZeros();
}

Eigen::VectorXd MumpsLu::solve(const Eigen::VectorXd& b) {
  Mumps& m = *mumps_;
  DMUMPS_STRUC_C& id = m.id;
  if (!m.analysed) throw std::logic_error("MumpsLu::solve before factorise");
  if (b.size() != id.n) throw std::invalid_argument("MumpsLu::solve: wrong right-hand side size");
  m.rhs.assign(b.data(), b.data() + b.size());
  id.rhs = m.rhs.data();
  id.nrhs = 1;
  id.lrhs = id.n;
  m.run(kJobSolve);
  if (infog(id, 1) < 0)
    throw std::runtime_error(fmt::format("EfgModel '{}': sparse LU solve failed: {}", name_, describe(id)));
  return Eigen::Map<const Eigen::VectorXd>(m.rhs.data(), id.n);
}

}  // namespace meshless
