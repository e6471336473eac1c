// The built-in lung's surface as a fixed polyhedron (an ASCII STL in mm), for the linear lab's polyhedral family
// (README.md here): every FEM level then meshes the same, exactly represented body, so no level's faceting of the
// curved surface differs from another's. The solid is built as core/geometry.cpp's add_builtin_lung() builds it.
//
//   g++ -O1 results/verify/linear_lab/make_polyhedral_lung.cpp -o /tmp/make_polyhedral_lung -lgmsh
//   /tmp/make_polyhedral_lung 16 results/verify/linear_lab/polyhedral_lung_16mm.stl
#include <gmsh.h>

#include <cstdio>
#include <cstdlib>
#include <vector>

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s SIZE_MM OUT.stl\n", argv[0]);
    return 2;
  }
  const double size = std::atof(argv[1]);
  gmsh::initialize();
  gmsh::option::setNumber("General.Terminal", 0);
  const int body = gmsh::model::occ::addSphere(0, 0, 0, 1);
  gmsh::model::occ::dilate({{3, body}}, 0, 0, 0, 78, 85, 135);
  const int medial = gmsh::model::occ::addBox(62, -300, -300, 300, 600, 600);
  const int diaphragm = gmsh::model::occ::addSphere(0, 0, -135 - 170 + 30, 170);
  gmsh::vectorpair out;
  std::vector<gmsh::vectorpair> out_map;
  gmsh::model::occ::cut({{3, body}}, {{3, medial}, {3, diaphragm}}, out, out_map);
  gmsh::model::occ::synchronize();
  gmsh::option::setNumber("Mesh.MeshSizeMax", size);
  gmsh::option::setNumber("Mesh.MeshSizeMin", size);
  gmsh::model::mesh::generate(2);
  gmsh::option::setNumber("Mesh.Binary", 0);
  gmsh::write(argv[2]);
  gmsh::finalize();
  return 0;
}
