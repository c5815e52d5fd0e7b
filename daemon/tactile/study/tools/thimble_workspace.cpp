// Prints the reachable workspace of the 3-RRS thimble described by a device YAML file:
// height range at zero tilt, the tilt reachable in every direction, and a height x tilt map.
//
//   thimble_workspace [config/devices/thimble.yaml]

#include <cmath>
#include <cstdio>
#include <exception>
#include <numbers>

#include "haptic/config/device.hpp"
#include "haptic/tactile/thimble_kinematics.hpp"

namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

// Largest tilt reachable in all directions at height h (bisection per direction).
double tiltAllDirections(const haptic::tactile::ThimbleKinematics& kinematics, double h) {
    double worst = kinematics.config().max_tilt_rad;
    for (int d = 0; d < 72; ++d) {
        const double angle = 2.0 * std::numbers::pi * d / 72.0;
        auto ok = [&](double t) {
            return kinematics.inverse({h, t * std::cos(angle), t * std::sin(angle)}).ok();
        };
        if (!ok(0.0)) {
            return -1.0;
        }
        if (ok(worst)) {
            continue;
        }
        double lo = 0.0;
        double hi = worst;
        for (int i = 0; i < 30; ++i) {
            const double mid = 0.5 * (lo + hi);
            (ok(mid) ? lo : hi) = mid;
        }
        worst = lo;
    }
    return worst;
}

}  // namespace

int main(int argc, char** argv) {
    const char* path = argc > 1 ? argv[1] : HAPTIC_DEFAULT_THIMBLE_CONFIG;
    try {
        const auto device = haptic::config::loadDeviceConfig(path);
        const haptic::tactile::ThimbleKinematics kinematics(device.thimble());
        const auto& ws = kinematics.workspace();
        const auto& cfg = device.thimble();
        const auto reach = kinematics.tiltReach();
        std::printf("thimble workspace from %s\n", path);
        std::printf(
            "  indentation limit: plate height >= %.2f mm (contact %.2f mm - max %.2f mm)\n",
            kinematics.minHeightM() * 1e3, cfg.finger_calibration.contact_height_m * 1e3,
            cfg.finger_calibration.max_indentation_m * 1e3);
        std::printf("  height at zero tilt: %.3f .. %.3f mm\n", ws.min_height_m * 1e3,
                    ws.max_height_m * 1e3);
        std::printf("  retract pose: height %.3f mm, zero tilt\n",
                    kinematics.retractPose().height_m * 1e3);
        std::printf(
            "  tilt reachable in every direction: %.2f deg at height %.2f mm "
            "(max_tilt_deg %.1f)\n",
            reach.max_tilt_rad * kDegPerRad, reach.best_height_m * 1e3,
            cfg.max_tilt_rad * kDegPerRad);
        std::printf("  height_mm  tilt_all_directions_deg  servo_deg_at_zero_tilt\n");
        for (int k = 0; k <= 10; ++k) {
            const double h = ws.min_height_m + (ws.max_height_m - ws.min_height_m) * k / 10.0;
            const auto ik = kinematics.inverse({h, 0.0, 0.0});
            std::printf("  %9.3f  %23.2f  %22.2f\n", h * 1e3,
                        tiltAllDirections(kinematics, h) * kDegPerRad,
                        ik.ok() ? ik.servo_rad[0] * kDegPerRad : NAN);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "thimble_workspace: %s\n", e.what());
        return 1;
    }
    return 0;
}
