#include "haptic/softhand/hand_builder.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace haptic::softhand {

namespace {

using config::Finger;

// Lateral offset (y) of each finger's MCP on the palm, in hand breadths; thumb is special.
double fingerOffset(Finger f) {
    switch (f) {
        case Finger::kThumb:
            return -0.55;
        case Finger::kIndex:
            return -0.375;
        case Finger::kMiddle:
            return -0.125;
        case Finger::kRing:
            return 0.125;
        case Finger::kLittle:
            return 0.375;
    }
    return 0.0;
}

double fingerRadiusScale(Finger f) {
    switch (f) {
        case Finger::kThumb:
            return 1.15;
        case Finger::kLittle:
            return 0.85;
        default:
            return 1.0;
    }
}

double distanceToSegment(const Vec3& p, double x0, double x1) {
    const double x = std::clamp(p.x(), x0, x1);
    return (p - Vec3(x, 0.0, 0.0)).norm();
}

// Tissue around a bone lying on the local x axis from 0 to length: a capsule for the
// fingertip (the pad), a flat-ended cylinder elsewhere.
TetMesh segmentMesh(double length, double radius, bool rounded_tip, int cells_across) {
    const double cell = 2.0 * radius / cells_across;
    const double x_end = rounded_tip ? length + radius : length;
    const int cells_x = std::max(2, static_cast<int>(std::ceil(x_end / cell)));
    const TetMesh grid = makeBoxMesh(Vec3(0.0, -radius, -radius), Vec3(x_end, radius, radius),
                                     {cells_x, cells_across, cells_across});
    return carveMesh(grid, [&](const Vec3& p) {
        return rounded_tip ? distanceToSegment(p, 0.0, length) <= radius
                           : std::hypot(p.y(), p.z()) <= radius;
    });
}

struct Builder {
    const config::HandConfig& hand;
    const HandBuildOptions& options;
    HandModel& model;

    Simulation& sim() { return model.simulation; }

    // A bone from `origin` along `direction` (unit, in the x-z plane), with its tissue.
    int addPhalanx(const std::string& name, Finger finger, Segment segment, const Vec3& origin,
                   const Mat3& rotation, double length, double radius, bool pad) {
        const double bone_radius = 0.35 * radius;
        RigidBodyDesc body;
        body.mass_kg =
            options.bone_density_kg_per_m3 * std::numbers::pi * bone_radius * bone_radius * length;
        const double axial = 0.5 * body.mass_kg * bone_radius * bone_radius;
        const double transverse =
            body.mass_kg * (3.0 * bone_radius * bone_radius + length * length) / 12.0;
        body.inertia_body_kg_m2 = Vec3(axial, transverse, transverse).asDiagonal();
        body.rotation = rotation;
        body.position_m = origin + rotation * Vec3(0.5 * length, 0.0, 0.0);
        const int b = sim().addBody(body);

        TetMesh mesh = segmentMesh(length, radius, pad, cellsAcross(hand.resolution));
        for (auto& p : mesh.nodes_m) {
            p = origin + rotation * p;
        }
        const int first = sim().addTissue(mesh, options.tissue);
        const double cell = 2.0 * radius / cellsAcross(hand.resolution);
        const double attach_radius = std::max(bone_radius, 0.6 * cell);
        int attached = 0;
        for (int i = first; i < sim().nodeCount(); ++i) {
            const Vec3 local = rotation.transpose() * (sim().nodePosition(i) - origin);
            if (distanceToSegment(local, 0.0, length) <= attach_radius) {
                sim().attachNode(i, b, options.coupling_stiffness_n_per_m);
                ++attached;
            }
        }
        if (attached == 0) {
            throw std::logic_error("hand builder: no tissue node close enough to bone " + name);
        }
        // Below resolution 2 the grid's nearest ring lies outside the bone, so only nodes on
        // its axis attach, and the tissue could turn about the bone with no energy at all: the
        // friction of a slide over an edge spun the fingertip's pad to its side, for good. The
        // nearest ring is therefore held against turning about the bone, along the tangent
        // only (the pad's compression stays as it was), by what the tissue in between would
        // give: the shear stiffness of one cell, G * cell.
        double off_axis = 0.0;
        for (int i = first; i < sim().nodeCount(); ++i) {
            const Vec3 local = rotation.transpose() * (sim().nodePosition(i) - origin);
            if (distanceToSegment(local, 0.0, length) <= attach_radius) {
                off_axis = std::max(off_axis, std::hypot(local.y(), local.z()));
            }
        }
        if (off_axis < 0.25 * cell) {
            const double shear_modulus_pa =
                options.tissue.youngs_modulus_pa / (2.0 * (1.0 + options.tissue.poisson_ratio));
            // Rings along the bone only: the end faces (x = 0, x = length, up to rounding)
            // stay free where they meet the next phalanx's tissue at the joint.
            const double end_tolerance = 1e-6 * length;
            for (int i = first; i < sim().nodeCount(); ++i) {
                const Vec3 local = rotation.transpose() * (sim().nodePosition(i) - origin);
                const double radial = std::hypot(local.y(), local.z());
                if (local.x() < end_tolerance || local.x() > length - end_tolerance ||
                    radial <= attach_radius || radial > 1.5 * cell) {
                    continue;
                }
                const Vec3 tangent_local(0.0, -local.z() / radial, local.y() / radial);
                sim().attachNodeAlong(i, b, rotation * tangent_local, shear_modulus_pa * cell);
            }
        }
        sim().setTrackingStiffness(b, options.tracking_linear_n_per_m,
                                   options.tracking_angular_nm_per_rad);
        model.bones.push_back(
            {name, finger, segment, b, length, body.position_m, first, sim().nodeCount() - first});
        return b;
    }

    int addJoint(JointType type, int a, int b, const Vec3& anchor, const Mat3& rotation,
                 double min_rad, double max_rad) {
        JointDesc joint;
        joint.type = type;
        joint.body_a = a;
        joint.body_b = b;
        joint.anchor_world_m = anchor;
        joint.axis_world = rotation * Vec3::UnitY();
        joint.twist_world = rotation * Vec3::UnitX();
        joint.positional_stiffness_n_per_m = options.joint_stiffness_n_per_m;
        joint.alignment_stiffness_nm_per_rad = options.joint_alignment_nm_per_rad;
        joint.limit_min_rad = min_rad;
        joint.limit_max_rad = max_rad;
        joint.limit_stiffness_nm_per_rad = options.joint_limit_nm_per_rad;
        const int j = sim().addJoint(joint);
        model.joints.push_back(j);
        return j;
    }

    void addFinger(Finger finger, const Vec3& mcp, const Mat3& rotation, int palm) {
        const auto lengths = phalanxLengths(finger, hand.anthropometry.hand_length_m);
        const double radius =
            0.5 * hand.anthropometry.fingertip_diameter_m * fingerRadiusScale(finger);
        const std::string base(config::toString(finger));
        static constexpr std::array<Segment, 3> kSegments{Segment::kProximal, Segment::kMiddle,
                                                          Segment::kDistal};
        static constexpr std::array<const char*, 3> kNames{"_proximal", "_middle", "_distal"};
        Vec3 origin = mcp;
        int previous = palm;
        for (int s = 0; s < 3; ++s) {
            const int b = addPhalanx(base + kNames[s], finger, kSegments[s], origin, rotation,
                                     lengths[s], radius * (1.08 - 0.04 * s), s == 2);
            if (previous >= 0) {
                if (s == 0) {
                    addJoint(JointType::kUniversal, previous, b, origin, rotation, -0.35, 1.57);
                } else {
                    addJoint(JointType::kHinge, previous, b, origin, rotation, 0.0,
                             s == 1 ? 1.75 : 1.4);
                }
            }
            previous = b;
            origin += rotation * Vec3(lengths[s], 0.0, 0.0);
        }
    }
};

}  // namespace

int cellsAcross(int resolution) {
    if (resolution < 0 || resolution > 8) {
        throw std::invalid_argument("hand resolution must be in 0..8");
    }
    return 2 + 2 * resolution;
}

std::array<double, 3> phalanxLengths(config::Finger finger, double hand_length_m) {
    static constexpr std::array<double, 3> kIndex{0.226, 0.132, 0.095};
    double scale = 1.0;
    switch (finger) {
        case Finger::kThumb:
            return {0.17 * hand_length_m, 0.16 * hand_length_m, 0.12 * hand_length_m};
        case Finger::kIndex:
            scale = 1.0;
            break;
        case Finger::kMiddle:
            scale = 1.08;
            break;
        case Finger::kRing:
            scale = 1.02;
            break;
        case Finger::kLittle:
            scale = 0.82;
            break;
    }
    return {kIndex[0] * scale * hand_length_m, kIndex[1] * scale * hand_length_m,
            kIndex[2] * scale * hand_length_m};
}

const BoneInfo* HandModel::findBone(const std::string& name) const {
    for (const auto& bone : bones) {
        if (bone.name == name) {
            return &bone;
        }
    }
    return nullptr;
}

HandModel buildHand(const config::HandConfig& hand, const SolverSettings& settings,
                    const HandBuildOptions& options) {
    const auto& a = hand.anthropometry;
    if (!(a.hand_length_m > 0.0) || !(a.hand_breadth_m > 0.0) || !(a.fingertip_diameter_m > 0.0)) {
        throw std::invalid_argument("hand builder: anthropometry must be positive");
    }
    HandModel model{Simulation(settings), {}, {}, -1};
    Builder builder{hand, options, model};
    const double palm_length = 0.45 * a.hand_length_m;
    const double palm_thickness = 1.6 * a.fingertip_diameter_m;
    if (hand.model == config::HandModel::kFingertip) {
        const Finger finger = hand.finger.value_or(Finger::kIndex);
        const auto lengths = phalanxLengths(finger, a.hand_length_m);
        builder.addPhalanx(std::string(config::toString(finger)) + "_distal", finger,
                           Segment::kDistal, Vec3::Zero(), Mat3::Identity(), lengths[2],
                           0.5 * a.fingertip_diameter_m * fingerRadiusScale(finger), true);
        return model;
    }
    // The palm: a rigid block. Kinematic for a single finger (the exoskeleton is grounded on
    // the back of the hand), dynamic and tracked for the whole hand.
    RigidBodyDesc palm;
    palm.mass_kg = 0.25 * a.hand_length_m / 0.19;
    const Vec3 half(0.5 * palm_length, 0.5 * a.hand_breadth_m, 0.5 * palm_thickness);
    palm.inertia_body_kg_m2 = Vec3(palm.mass_kg / 3.0 * (half.y() * half.y() + half.z() * half.z()),
                                   palm.mass_kg / 3.0 * (half.x() * half.x() + half.z() * half.z()),
                                   palm.mass_kg / 3.0 * (half.x() * half.x() + half.y() * half.y()))
                                  .asDiagonal();
    palm.kinematic = hand.model == config::HandModel::kFinger;
    model.palm_body = model.simulation.addBody(palm);
    model.bones.push_back({"palm", std::nullopt, Segment::kPalm, model.palm_body, palm_length,
                           Vec3::Zero(), model.simulation.nodeCount(), 0});
    if (!palm.kinematic) {
        model.simulation.setTrackingStiffness(model.palm_body,
                                              10.0 * options.tracking_linear_n_per_m,
                                              10.0 * options.tracking_angular_nm_per_rad);
    }
    std::vector<Finger> fingers;
    if (hand.model == config::HandModel::kFinger) {
        fingers.push_back(hand.finger.value_or(Finger::kIndex));
    } else {
        // Always in thumb..little order, whatever order the scene lists them in.
        for (Finger f :
             {Finger::kThumb, Finger::kIndex, Finger::kMiddle, Finger::kRing, Finger::kLittle}) {
            if (hand.simulates(f)) {
                fingers.push_back(f);
            }
        }
    }
    for (Finger f : fingers) {
        const double y = fingerOffset(f) * a.hand_breadth_m;
        if (f == Finger::kThumb) {
            // Thumb from the palm's proximal radial corner, opposed: pointing forward-inward
            // and rotated about its own axis so it flexes towards the palm.
            const Mat3 rotation =
                (Eigen::AngleAxisd(-0.6, Vec3::UnitZ()) * Eigen::AngleAxisd(1.2, Vec3::UnitX()))
                    .toRotationMatrix();
            builder.addFinger(f, Vec3(-0.15 * palm_length, y, -0.25 * palm_thickness), rotation,
                              model.palm_body);
        } else {
            builder.addFinger(f, Vec3(0.5 * palm_length, y, 0.0), Mat3::Identity(),
                              model.palm_body);
        }
    }
    return model;
}

}  // namespace haptic::softhand
