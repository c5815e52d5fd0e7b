#pragma once

// Procedural hand model from the scene's anthropometry (no mesh files exist here). Bones are
// rigid bodies (palm block, three phalanges per finger); tissue is a tetrahedral capsule or
// cylinder around each bone, at `resolution` cells across the finger; joints are soft hinges
// (PIP, DIP, thumb IP) and universal joints (MCP, thumb MCP) with limits.
//
// Frame at build time: the palm's centre at the origin, fingers along +x, palm facing -z,
// flexion = positive rotation about +y (curls the tip towards -z). Only what the scene needs
// is built: a fingertip (distal phalanx + pad), one finger (3 phalanges on a kinematic
// palm), or the hand (palm and the scene's `fingers`, all five by default).

#include <optional>
#include <string>
#include <vector>

#include "haptic/config/scene.hpp"
#include "haptic/softhand/simulation.hpp"

namespace haptic::softhand {

enum class Segment { kPalm, kProximal, kMiddle, kDistal };

struct BoneInfo {
    std::string name;  // e.g. "index_distal"
    std::optional<config::Finger> finger;
    Segment segment{Segment::kPalm};
    int body{-1};
    double length_m{0.0};
    Vec3 rest_position_m{Vec3::Zero()};  // body centre at build time
    int first_node{0};                   // its tissue: nodes [first_node, first_node + nodes)
    int node_count{0};
};

struct HandBuildOptions {
    TissueMaterial tissue;
    double bone_density_kg_per_m3{1900.0};
    double coupling_stiffness_n_per_m{200.0};  // U_st per node
    double joint_stiffness_n_per_m{2000.0};    // positional
    double joint_alignment_nm_per_rad{0.5};
    double joint_limit_nm_per_rad{2.0};
    double tracking_linear_n_per_m{200.0};  // U_crb
    double tracking_angular_nm_per_rad{0.2};
};

struct HandModel {
    Simulation simulation;
    std::vector<BoneInfo> bones;
    std::vector<int> joints;
    int palm_body{-1};  // -1 for the fingertip model

    [[nodiscard]] const BoneInfo* findBone(const std::string& name) const;
};

// Segment lengths of a finger as fractions of the hand length (index about 43/25/18 mm for a
// 19 cm hand; docs/algorithms.md §5.8 gives 40-45 / 22-26 / 17-20 mm).
[[nodiscard]] std::array<double, 3> phalanxLengths(config::Finger finger, double hand_length_m);

[[nodiscard]] HandModel buildHand(const config::HandConfig& hand, const SolverSettings& settings,
                                  const HandBuildOptions& options = {});

// Tissue cells across the finger diameter for a resolution level (0..8): 2 + 2 level.
[[nodiscard]] int cellsAcross(int resolution);

}  // namespace haptic::softhand
