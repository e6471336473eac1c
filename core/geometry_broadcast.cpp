#include "core/geometry_broadcast.hpp"

#include <climits>
#include <cstdint>

#include <array>
#include <stdexcept>
#include <string>
#include <vector>

namespace core {
namespace {

template <typename T>
MPI_Datatype mpi_type();
template <>
MPI_Datatype mpi_type<double>() { return MPI_DOUBLE; }
template <>
MPI_Datatype mpi_type<int>() { return MPI_INT; }
template <>
MPI_Datatype mpi_type<char>() { return MPI_CHAR; }
template <>
MPI_Datatype mpi_type<long long>() { return MPI_LONG_LONG; }

/// Rank 0's `count` values at `data` on every process (MPI counts are int: a larger array is refused).
template <typename T>
void broadcast(T* data, std::size_t count, MPI_Comm communicator) {
  if (count > static_cast<std::size_t>(INT_MAX))
    throw std::runtime_error("geometry broadcast: an array of " + std::to_string(count) +
                             " values exceeds one MPI message");
  MPI_Bcast(data, static_cast<int>(count), mpi_type<T>(), 0, communicator);
}

/// Rank 0's strings on every process (each sent as its length, then its characters).
void broadcast_strings(std::vector<std::string>* strings, MPI_Comm communicator) {
  long long n = static_cast<long long>(strings->size());
  broadcast(&n, 1, communicator);
  strings->resize(static_cast<std::size_t>(n));
  for (std::string& s : *strings) {
    long long length = static_cast<long long>(s.size());
    broadcast(&length, 1, communicator);
    s.resize(static_cast<std::size_t>(length));
    if (length > 0) broadcast(s.data(), s.size(), communicator);
  }
}

/// Rank 0's rows x cols array (Eigen storage) on every process.
template <typename Matrix>
void broadcast_matrix(Matrix* m, MPI_Comm communicator) {
  std::array<long long, 2> shape{static_cast<long long>(m->rows()), static_cast<long long>(m->cols())};
  broadcast(shape.data(), 2, communicator);
  m->resize(shape[0], shape[1]);
  broadcast(m->data(), static_cast<std::size_t>(m->size()), communicator);
}

template <typename T>
void broadcast_vector(std::vector<T>* v, MPI_Comm communicator) {
  long long size = static_cast<long long>(v->size());
  broadcast(&size, 1, communicator);
  v->resize(static_cast<std::size_t>(size));
  broadcast(v->data(), v->size(), communicator);
}

/// Rank 0's mesh on every process.
void broadcast_mesh(core::TetMesh* mesh, MPI_Comm communicator) {
  broadcast_matrix(&mesh->vertices, communicator);
  broadcast_matrix(&mesh->tets, communicator);
  broadcast_matrix(&mesh->boundary_faces, communicator);
  std::vector<int> tag_values(mesh->face_tags.size());
  for (std::size_t i = 0; i < tag_values.size(); ++i) tag_values[i] = static_cast<int>(mesh->face_tags[i]);
  broadcast_vector(&tag_values, communicator);
  mesh->face_tags.resize(tag_values.size());
  for (std::size_t i = 0; i < tag_values.size(); ++i) mesh->face_tags[i] = static_cast<core::FaceTag>(tag_values[i]);
  broadcast_vector(&mesh->vertex_fixed, communicator);
}

enum class Outcome : int { built = 0, case_error = 1, other_error = 2 };

}  // namespace

core::Geometry build_on_rank_zero(const std::function<core::Geometry()>& build, MPI_Comm communicator) {
  int n_processes = 1, rank = 0;
  MPI_Comm_size(communicator, &n_processes);
  MPI_Comm_rank(communicator, &rank);
  if (n_processes == 1) return build();
  const bool root = rank == 0;
  core::Geometry g;
  Outcome outcome = Outcome::built;
  std::vector<std::string> error(3);  // message; for a CaseError: file, JSON path
  if (root) {
    try {
      g = build();
    } catch (const core::CaseError& e) {
      outcome = Outcome::case_error;
      error = {e.what(), e.file(), e.json_path()};
    } catch (const std::exception& e) {
      outcome = Outcome::other_error;
      error[0] = e.what();
    } catch (const std::string& e) {  // the Gmsh SDK throws its last error as a string
      outcome = Outcome::other_error;
      error[0] = "Gmsh: " + e;
    }
  }
  int code = static_cast<int>(outcome);
  MPI_Bcast(&code, 1, MPI_INT, 0, communicator);
  outcome = static_cast<Outcome>(code);
  if (outcome != Outcome::built) {
    broadcast_strings(&error, communicator);
    if (outcome == Outcome::case_error) {
      // CaseError's message is "file: path: expected"; hand the expected part back to its constructor.
      const std::string prefix = error[1] + ": " + (error[2].empty() ? std::string("/") : error[2]) + ": ";
      const std::string& message = error[0];
      throw core::CaseError(error[1], error[2],
                            message.rfind(prefix, 0) == 0 ? message.substr(prefix.size()) : message);
    }
    throw std::runtime_error(error[0]);
  }

  broadcast_mesh(&g.fem_mesh, communicator);
  broadcast_mesh(&g.meshless_mesh, communicator);  // empty unless the build made the node cloud
  broadcast_matrix(&g.sample_points, communicator);
  std::array<double, 7> small{g.load_centre.x(), g.load_centre.y(), g.load_centre.z(), g.load_normal.x(),
                              g.load_normal.y(),  g.load_normal.z(), g.reference_volume};
  MPI_Bcast(small.data(), 7, MPI_DOUBLE, 0, communicator);
  g.load_centre = Eigen::Vector3d(small[0], small[1], small[2]);
  g.load_normal = Eigen::Vector3d(small[3], small[4], small[5]);
  g.reference_volume = small[6];
  // The cut: every process locates the samples next to it on their lip (SampleEvaluator), so each needs it.
  // Sent as what defines it (trace, direction, depth, extension) and rebuilt, which gives the same surface.
  int has_cut = g.cut ? 1 : 0;
  MPI_Bcast(&has_cut, 1, MPI_INT, 0, communicator);
  if (has_cut) {
    Eigen::Matrix<double, 3, Eigen::Dynamic> top;
    std::array<double, 5> shape{};
    if (root) {
      top.resize(3, static_cast<Eigen::Index>(g.cut->top().size()));
      for (std::size_t i = 0; i < g.cut->top().size(); ++i) top.col(static_cast<Eigen::Index>(i)) = g.cut->top()[i];
      shape = {g.cut->direction().x(), g.cut->direction().y(), g.cut->direction().z(), g.cut->depth(),
               g.cut->extension()};
    }
    broadcast_matrix(&top, communicator);
    MPI_Bcast(shape.data(), 5, MPI_DOUBLE, 0, communicator);
    if (!root) {
      std::vector<Eigen::Vector3d> points(static_cast<std::size_t>(top.cols()));
      for (std::size_t i = 0; i < points.size(); ++i) points[i] = top.col(static_cast<Eigen::Index>(i));
      g.cut.emplace(std::move(points), Eigen::Vector3d(shape[0], shape[1], shape[2]), shape[3], shape[4]);
    }
  }
  return g;
}

}  // namespace core
