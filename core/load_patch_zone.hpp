#pragma once
// The zone under the probe where the meshes are refined to the load patch's size (core/geometry.cpp,
// refine_regions; GeometrySpec::load_patch_size for the FEM mesh): a ball about the load centre, beyond which the
// size grows to the mesh size over one more load radius. A mesh study refines the samples inside the ball at the
// patch's rate (like h^g, /geometry/refinement/load_patch_grading g) and those beyond it like h, so `tissue verify
// fem` reports the two groups' observed orders apart (experiments/comparator/mesh_study_estimate.hpp). With the
// grading zone "edge" (/geometry/refinement/load_patch_grading_zone) only a band along the patch's edge is graded and
// the ball keeps load_patch_refinement * h, so both groups fall like h.

namespace core {

/// The refined ball's radius, in load radii (/load/radius).
constexpr double kLoadPatchBallRadii = 1.5;

}  // namespace core
