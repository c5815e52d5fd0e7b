#pragma once

// Procedural tetrahedral meshes. No mesh files exist in this project, so every tissue mesh
// is a structured grid (optionally graded) cut into tetrahedra and carved to a shape.

#include <array>
#include <functional>
#include <vector>

#include "haptic/softhand/rotation.hpp"

namespace haptic::softhand {

struct TetMesh {
    std::vector<Vec3> nodes_m;
    std::vector<std::array<int, 4>> tets;  // positively oriented (signed volume > 0)
};

// Grid with the given node coordinates per axis (strictly increasing, >= 2 each), every hex
// cut into 6 tetrahedra along its main diagonal (Kuhn split). Adjacent cells share faces, so
// the mesh is conforming. Graded coordinates put resolution where a test needs it.
[[nodiscard]] TetMesh makeGridMesh(const std::vector<double>& xs_m, const std::vector<double>& ys_m,
                                   const std::vector<double>& zs_m);

// Uniform box [lo, hi] with `cells` hexes per axis.
[[nodiscard]] TetMesh makeBoxMesh(const Vec3& lo_m, const Vec3& hi_m, std::array<int, 3> cells);

// `count` + 1 coordinates from a to b whose spacing grows geometrically by `ratio` per cell
// (ratio 1 = uniform). Used to refine a mesh towards a contact point.
[[nodiscard]] std::vector<double> gradedCoordinates(double a_m, double b_m, int count,
                                                    double ratio);

// Keeps the tetrahedra whose centroid satisfies `inside` and drops nodes no longer used.
[[nodiscard]] TetMesh carveMesh(const TetMesh& mesh,
                                const std::function<bool(const Vec3&)>& inside);

// Nodes on the boundary surface (faces used by exactly one tetrahedron), sorted.
[[nodiscard]] std::vector<int> surfaceNodes(const TetMesh& mesh);

[[nodiscard]] double signedVolume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

}  // namespace haptic::softhand
