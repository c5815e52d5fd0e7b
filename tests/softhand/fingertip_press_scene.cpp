#include "fingertip_press_scene.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>

namespace haptic::softhand::bench {

config::HandConfig handConfig(config::HandModel model, int resolution) {
    config::HandConfig hand;
    hand.model = model;
    hand.finger = config::Finger::kIndex;
    hand.resolution = resolution;
    hand.anthropometry = {0.19, 0.085, 0.016};
    return hand;
}

SolverSettings solverSettings(int pcg_cap, double pcg_tolerance) {
    SolverSettings settings;
    settings.pcg_max_iterations = pcg_cap;
    settings.pcg_relative_tolerance = pcg_tolerance;
    settings.contact_stiffness_n_per_m = kContactStiffnessNPerM;
    return settings;
}

Vec3 pressTargetOffset(int step) {
    const double t = (step % kCycleSteps) * kDt;
    const double press = t < 0.2 ? t / 0.2 : (t < 0.8 ? 1.0 : (1.0 - t) / 0.2);
    const double slide = t < 0.2 ? 0.0 : std::min(1.0, (t - 0.2) / 0.6);
    return {0.01 * slide, 0.0, -0.005 * press};
}

FingertipPress::FingertipPress(int level, int pcg_cap, double pcg_tolerance)
    : model_(buildHand(handConfig(config::HandModel::kFingertip, level),
                       solverSettings(pcg_cap, pcg_tolerance))) {
    table_ = model_.simulation.addCollider(
        {HalfSpace{}, Vec3(0.0, 0.0, kTableHeightM), Mat3::Identity(), kTableFriction});
    bone_ = model_.bones.front().body;
    start_ = model_.simulation.bodyPosition(bone_);
}

void FingertipPress::setInput(int step) {
    model_.simulation.setTrackingTarget(bone_, start_ + pressTargetOffset(step), Mat3::Identity());
}

Sample FingertipPress::sample() const {
    return {model_.simulation.forceOnCollider(table_).z(), model_.simulation.bodyPosition(bone_)};
}

namespace {

double distanceToBone(const Vec3& p, double length) {
    const double x = std::clamp(p.x(), 0.0, length);
    return (p - Vec3(x, 0.0, 0.0)).norm();
}

}  // namespace

// Mirrors hand_builder.cpp (segmentMesh, addPhalanx) for the fingertip model, which leaves the
// bone at the origin along +x; bullet_deformable_test checks the result node for node
// against buildHand, so a change to the builder shows up there.
FingertipModel fingertipModel(int level) {
    const config::HandConfig hand = handConfig(config::HandModel::kFingertip, level);
    const HandBuildOptions options;
    const double length = phalanxLengths(*hand.finger, hand.anthropometry.hand_length_m)[2];
    const double radius = 0.5 * hand.anthropometry.fingertip_diameter_m;
    const int cells_across = cellsAcross(level);
    const double cell = 2.0 * radius / cells_across;
    const int cells_x = std::max(2, static_cast<int>(std::ceil((length + radius) / cell)));
    FingertipModel model;
    model.mesh =
        carveMesh(makeBoxMesh(Vec3(0.0, -radius, -radius), Vec3(length + radius, radius, radius),
                              {cells_x, cells_across, cells_across}),
                  [&](const Vec3& p) { return distanceToBone(p, length) <= radius; });
    model.material = options.tissue;
    const double bone_radius = 0.35 * radius;
    model.bone_mass_kg =
        options.bone_density_kg_per_m3 * std::numbers::pi * bone_radius * bone_radius * length;
    model.bone_inertia_kg_m2 =
        Vec3(0.5 * model.bone_mass_kg * bone_radius * bone_radius,
             model.bone_mass_kg * (3.0 * bone_radius * bone_radius + length * length) / 12.0,
             model.bone_mass_kg * (3.0 * bone_radius * bone_radius + length * length) / 12.0);
    model.bone_position_m = Vec3(0.5 * length, 0.0, 0.0);
    const double attach_radius = std::max(bone_radius, 0.6 * cell);
    for (std::size_t i = 0; i < model.mesh.nodes_m.size(); ++i) {
        if (distanceToBone(model.mesh.nodes_m[i], length) <= attach_radius) {
            model.bone_nodes.push_back(static_cast<int>(i));
        }
    }
    model.tracking_linear_n_per_m = options.tracking_linear_n_per_m;
    model.tracking_angular_nm_per_rad = options.tracking_angular_nm_per_rad;
    return model;
}

std::vector<Sample> pressReference(const char* cache_path) {
    std::vector<Sample> trace;
    const bool cached = cache_path != nullptr && cache_path[0] != '\0';
    if (cached) {
        if (std::FILE* in = std::fopen(cache_path, "r")) {
            Sample s{};
            while (std::fscanf(in, "%lf %lf %lf %lf", &s.table_force_n, &s.tip_m.x(), &s.tip_m.y(),
                               &s.tip_m.z()) == 4) {
                trace.push_back(s);
            }
            std::fclose(in);
            if (trace.size() == static_cast<std::size_t>(kCycleSteps)) {
                return trace;
            }
            trace.clear();
        }
    }
    FingertipPress scene(kPressReferenceLevel, 2000, 1e-8);
    for (int s = 0; s < kCycleSteps; ++s) {
        scene.setInput(s);
        scene.step();
        trace.push_back(scene.sample());
    }
    if (cached) {
        if (std::FILE* out = std::fopen(cache_path, "w")) {
            for (const Sample& s : trace) {
                std::fprintf(out, "%.17g %.17g %.17g %.17g\n", s.table_force_n, s.tip_m.x(),
                             s.tip_m.y(), s.tip_m.z());
            }
            std::fclose(out);
        }
    }
    return trace;
}

TraceError traceError(const std::vector<Sample>& trace, const std::vector<Sample>& reference) {
    const std::size_t n = std::min(trace.size(), reference.size());
    if (n == 0) {
        throw std::invalid_argument("traceError: empty trace");
    }
    double force2 = 0.0;
    double force_ref2 = 0.0;
    double press2 = 0.0;
    double press_ref2 = 0.0;
    double tip2 = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
        const double df = trace[i].table_force_n - reference[i].table_force_n;
        const double f_ref = reference[i].table_force_n;
        force2 += df * df;
        force_ref2 += f_ref * f_ref;
        if (i < static_cast<std::size_t>(kPressSteps)) {
            press2 += df * df;
            press_ref2 += f_ref * f_ref;
        }
        tip2 += (trace[i].tip_m - reference[i].tip_m).squaredNorm();
    }
    return {std::sqrt(press2 / std::max(press_ref2, 1e-30)),
            std::sqrt(force2 / std::max(force_ref2, 1e-30)),
            1e3 * std::sqrt(tip2 / static_cast<double>(n))};
}

}  // namespace haptic::softhand::bench
