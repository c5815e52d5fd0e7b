// Error analysis of thimble rendering methods (ALGORITHMS §3.7): for each virtual contact,
// compare the force the device plate would press into the fingertip model with the force of
// the virtual contact, for the contact optimiser and the two baselines.
//
//   tactile_error_analysis [--config config/devices/thimble.yaml] [--out DIR]
//
// Writes DIR/error_analysis.md (the README table) and DIR/error_analysis.dat (gnuplot input,
// rendered by error_analysis.gp next to this file). Prints the table too.

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "haptic/config/device.hpp"
#include "haptic/tactile/baselines.hpp"
#include "haptic/tactile/contact_optimiser.hpp"
#include "haptic/tactile/fingertip_model.hpp"

namespace {

using haptic::tactile::ContactSurfaceOptimiser;
using haptic::tactile::FingertipContactModel;
using haptic::tactile::NonlinearPadModel;
using haptic::tactile::Obstacle;
using haptic::tactile::PlatformDofs;
using haptic::tactile::ThimbleKinematics;

constexpr double kDegPerRad = 180.0 / std::numbers::pi;
constexpr double kIndentationM = 0.0015;  // depth of every virtual contact past first touch

struct Case {
    std::string name;
    std::unique_ptr<Obstacle> object;
};

struct Metrics {
    bool valid{false};
    double force_error{0.0};      // |F_d - F_v| / |F_v|
    double magnitude_error{0.0};  // (|F_d| - |F_v|) / |F_v|, signed
    double direction_error_deg{0.0};
    double jaccard{0.0};
    double force_n{0.0};
};

// Outward normal tilted by angle_rad about the y axis away from -z (towards +x).
Eigen::Vector3d tiltedOutward(double angle_rad) {
    return {-std::sin(angle_rad), 0.0, -std::cos(angle_rad)};
}

std::vector<Case> makeCases(const NonlinearPadModel& pad) {
    const auto& p = pad.parameters();
    const Eigen::Vector3d pad_centre(0.0, 0.0, p.contact_height_m - p.pad_radius_m);
    std::vector<Case> cases;
    auto plane = [&](double angle_deg, double depth_m, const std::string& name) {
        const Eigen::Vector3d n = tiltedOutward(angle_deg / kDegPerRad);
        // Touches the pad sphere at pad_centre - R n, then moves depth_m into the finger.
        const Eigen::Vector3d point = pad_centre - (p.pad_radius_m - depth_m) * n;
        cases.push_back({name, std::make_unique<haptic::tactile::HalfSpaceObstacle>(point, n)});
    };
    for (const double angle : {0.0, 10.0, 20.0, 30.0}) {
        plane(angle, kIndentationM, "plane " + std::to_string(static_cast<int>(angle)) + " deg");
    }
    for (const double radius_mm : {5.0, 10.0, 20.0}) {
        const double r = radius_mm * 1e-3;
        const Eigen::Vector3d n = tiltedOutward(0.0);
        cases.push_back({"sphere r=" + std::to_string(static_cast<int>(radius_mm)) + " mm",
                         std::make_unique<haptic::tactile::SphereObstacle>(
                             pad_centre - (p.pad_radius_m + r - kIndentationM) * n, r)});
    }
    {
        const double r = 0.010;
        const Eigen::Vector3d n = tiltedOutward(20.0 / kDegPerRad);
        cases.push_back({"sphere r=10 mm, 20 deg",
                         std::make_unique<haptic::tactile::SphereObstacle>(
                             pad_centre - (p.pad_radius_m + r - kIndentationM) * n, r)});
    }
    {
        // Ridge along y, faces at +-45 degrees from the pad normal.
        const double s = std::sqrt(0.5);
        const Eigen::Vector3d na(s, 0.0, -s);
        const Eigen::Vector3d nb(-s, 0.0, -s);
        const Eigen::Vector3d ridge(0.0, 0.0, p.contact_height_m - kIndentationM);
        cases.push_back({"edge 90 deg",
                         std::make_unique<haptic::tactile::RightAngleEdgeObstacle>(ridge, na, nb)});
    }
    plane(45.0, kIndentationM, "plane 45 deg (> max tilt)");
    plane(0.0, 0.006, "plane 6 mm deep (> max indent)");
    return cases;
}

Metrics measure(const ThimbleKinematics& kinematics, const FingertipContactModel& pad,
                const haptic::tactile::PadContact& reference,
                const std::optional<PlatformDofs>& dofs) {
    Metrics m;
    if (!dofs) {
        return m;
    }
    const auto ik = kinematics.inverse(*dofs);
    if (!ik.ok()) {
        return m;
    }
    // The plate where the servos put it: forward kinematics of the commanded angles.
    const auto fk = kinematics.forward(ik.servo_rad, *dofs);
    if (!fk.ok()) {
        return m;
    }
    const auto device =
        pad.press(haptic::tactile::PlateObstacle(fk.pose, kinematics.config().plate_radius_m));
    const Eigen::Vector3d& fv = reference.force_on_finger_n;
    const Eigen::Vector3d& fd = device.force_on_finger_n;
    m.valid = true;
    m.force_n = fd.norm();
    m.force_error = (fd - fv).norm() / fv.norm();
    m.magnitude_error = (fd.norm() - fv.norm()) / fv.norm();
    m.direction_error_deg =
        fd.norm() > 0.0
            ? std::acos(std::clamp(fd.normalized().dot(fv.normalized()), -1.0, 1.0)) * kDegPerRad
            : 180.0;
    int both = 0;
    int either = 0;
    for (std::size_t i = 0; i < device.node_in_contact.size(); ++i) {
        both += device.node_in_contact[i] && reference.node_in_contact[i];
        either += device.node_in_contact[i] || reference.node_in_contact[i];
    }
    m.jaccard = either > 0 ? static_cast<double>(both) / either : 0.0;
    return m;
}

std::string cell(const Metrics& m) {
    if (!m.valid) {
        return " n/a |";
    }
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, " %.1f%% (%+.1f%%, %.1f°, J %.2f) |",
                  100.0 * m.force_error, 100.0 * m.magnitude_error, m.direction_error_deg,
                  m.jaccard);
    return buffer;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Force-error analysis of thimble rendering methods (ALGORITHMS §3.7)"};
    std::string config_path = HAPTIC_DEFAULT_THIMBLE_CONFIG;
    std::string out_dir = ".";
    app.add_option("--config", config_path, "thimble device YAML")->check(CLI::ExistingFile);
    app.add_option("--out", out_dir, "folder for error_analysis.md and .dat");
    std::string weighting_name = "stiffness";
    int sample_override = 0;
    app.add_option("--samples", sample_override, "pad samples (default optimiser.pad_samples)")
        ->check(CLI::Range(1, static_cast<int>(haptic::msgs::kMaxContactSamples)));
    app.add_option("--weighting", weighting_name, "sample weights the simulation sends")
        ->check(CLI::IsMember({"area", "force", "stiffness"}));
    CLI11_PARSE(app, argc, argv);
    try {
        const auto device = haptic::config::loadDeviceConfig(config_path);
        const ThimbleKinematics kinematics(device.thimble());
        haptic::tactile::PadModelParameters pad_parameters;
        pad_parameters.contact_height_m = device.thimble().finger_calibration.contact_height_m;
        const NonlinearPadModel pad(pad_parameters);
        // Linear finger stiffness for the force baseline: the secant of the pad model at the
        // cases' indentation, the most favourable single value for that baseline.
        const double stiffness = pad.flatPlateForce(kIndentationM) / kIndentationM;
        auto settings = haptic::tactile::OptimiserSettings::fromConfig(device.thimble());
        settings.max_samples = std::max(settings.max_samples, sample_override);
        ContactSurfaceOptimiser optimiser(kinematics, settings);
        int samples = device.thimble().optimiser.pad_samples;
        if (sample_override > 0) {
            samples = sample_override;
        }
        const auto weighting = weighting_name == "area" ? haptic::tactile::SampleWeighting::kArea
                               : weighting_name == "force"
                                   ? haptic::tactile::SampleWeighting::kContactForce
                                   : haptic::tactile::SampleWeighting::kContactStiffness;

        std::ostringstream table;
        std::ostringstream data;
        table << "| case | reachable | F_v (N) | optimiser | geometric plane | force-normal | "
                 "optimiser report |\n|---|---|---|---|---|---|---|\n";
        data << "# index name optimiser_error geometric_error force_error (percent)\n";
        int index = 0;
        for (const Case& c : makeCases(pad)) {
            const auto reference = pad.press(*c.object);
            const auto surface = pad.contactSurface(*c.object, samples, weighting);
            optimiser.reset();
            const auto command = optimiser.solve(surface);
            const Metrics ours = measure(kinematics, pad, reference, command.dofs);
            // The plane-fit baseline is defined on area weights: centroid and average normal.
            const auto area_surface =
                pad.contactSurface(*c.object, samples, haptic::tactile::SampleWeighting::kArea);
            const Metrics geometric =
                measure(kinematics, pad, reference, geometricPlaneFit(kinematics, area_surface));
            const Metrics force =
                measure(kinematics, pad, reference,
                        forceNormalDisplacement(kinematics, surface, reference.force_on_finger_n,
                                                stiffness));
            const auto& r = command.report;
            std::string active;
            for (int j = 0; j < haptic::tactile::kConstraintCount; ++j) {
                if (r.active_constraints & (1U << j)) {
                    active +=
                        std::string(active.empty() ? "" : "+") + haptic::tactile::constraintName(j);
                }
            }
            char report[160];
            std::snprintf(report, sizeof report, "%s, %d it, rms %.3f mm, active: %s",
                          r.converged ? "converged" : "NOT converged", r.iterations,
                          r.contact_rms_m * 1e3, active.empty() ? "none" : active.c_str());
            table << "| " << c.name << " | " << (r.clamped ? "no" : "yes") << " | "
                  << std::to_string(reference.force_on_finger_n.norm()).substr(0, 5) << " |"
                  << cell(ours) << cell(geometric) << cell(force) << " " << report << " |\n";
            auto pct = [](const Metrics& m) { return m.valid ? 100.0 * m.force_error : NAN; };
            data << index++ << " \"" << c.name << "\" " << pct(ours) << ' ' << pct(geometric) << ' '
                 << pct(force) << '\n';
        }
        table << "\nCells: force error |F_d - F_v| / |F_v| (signed magnitude error, direction "
                 "error, Jaccard overlap of the contact node sets). Finger stiffness for the "
                 "force-normal baseline: "
              << stiffness << " N/m (secant at " << kIndentationM * 1e3
              << " mm). Pad model: " << pad.nodeCount() << " nodes; optimiser input: " << samples
              << " samples.\n";
        std::printf("%s", table.str().c_str());
        std::filesystem::create_directories(out_dir);
        std::ofstream(std::filesystem::path(out_dir) / "error_analysis.md") << table.str();
        std::ofstream(std::filesystem::path(out_dir) / "error_analysis.dat") << data.str();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "tactile_error_analysis: %s\n", e.what());
        return 1;
    }
    return 0;
}
