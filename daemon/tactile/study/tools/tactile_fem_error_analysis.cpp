// The thimble's error analysis against the soft-hand FEM (docs/algorithms.md §3.7, issue #21):
// for each virtual contact, the force and moment the device plate presses into the FEM
// fingertip against those the virtual object presses into it, for the contact optimiser
// (cold and warm) and the two baselines.
//
//   tactile_fem_error_analysis [--config config/devices/thimble.yaml] [--resolution 1]
//                              [--indentation-mm 1.5] [--out DIR]
//
// Prints the optimiser's pad law fitted to the FEM (fem_pad_fit.hpp: the stiffening depth that
// config/devices/thimble.yaml's optimiser.pad_stiffening_depth_m ships) and the markdown table
// docs/benchmarks.md records, and writes DIR/fem_error_analysis.dat, the gnuplot input of
// daemon/tactile/study/results/fem_error_analysis.gp.

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "haptic/config/device.hpp"
#include "haptic/tactile/fem_error_analysis.hpp"
#include "haptic/tactile/fem_pad_fit.hpp"

namespace {

using haptic::tactile::FemMethodResult;

std::string cell(const FemMethodResult& m) {
    if (!m.valid) {
        return " n/a |";
    }
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, " %.1f %% (%+.1f %%, %.2f mm) |", 100.0 * m.force_error,
                  100.0 * m.magnitude_error, m.moment_error_mm);
    return buffer;
}

std::string report(const haptic::tactile::SolveReport& r) {
    char buffer[96];
    std::snprintf(buffer, sizeof buffer, "%s, %d it%s", r.converged ? "converged" : "NOT converged",
                  r.iterations, r.clamped ? ", clamped" : "");
    return buffer;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "Thimble force-error analysis against the FEM fingertip (docs/algorithms.md §3.7)"};
    std::string config_path = HAPTIC_DEFAULT_THIMBLE_CONFIG;
    std::string out_dir = ".";
    int resolution = 1;
    double indentation_mm = 1.5;
    app.add_option("--config", config_path, "thimble device YAML")->check(CLI::ExistingFile);
    app.add_option("--resolution", resolution, "FEM level (the thimble scene ships 1)")
        ->check(CLI::Range(0, 4));
    app.add_option("--indentation-mm", indentation_mm, "depth of every virtual contact")
        ->check(CLI::Range(0.1, 4.0));
    app.add_option("--out", out_dir, "folder for fem_error_analysis.dat (the gnuplot input)");
    CLI11_PARSE(app, argc, argv);
    std::string command = "tactile_fem_error_analysis";
    for (int i = 1; i < argc; ++i) {
        command += std::string(" ") + argv[i];
    }
    std::printf("# %s\n", command.c_str());
    try {
        const auto device = haptic::config::loadDeviceConfig(config_path);
        const haptic::tactile::ThimbleKinematics kinematics(device.thimble());
        const auto settings = haptic::tactile::OptimiserSettings::fromConfig(device.thimble());
        const haptic::tactile::FemFingertip finger(device.thimble(), resolution,
                                                   device.thimble().optimiser.pad_samples);
        const auto fit = haptic::tactile::fitPadLawToFem(finger, device.thimble().plate_radius_m,
                                                         haptic::tactile::defaultPadFitDepths());
        std::printf(
            "Pad law fitted to the FEM (flat plate): stiffening depth s = %.3f mm%s (shipped "
            "optimiser.pad_stiffening_depth_m: %.3f mm), weight scale c = %.3f, force error RMS "
            "%.1f %%, max %.1f %%\n\n| depth (mm) | FEM force (N) | fitted law (N) "
            "|\n|---|---|---|\n",
            fit.stiffening_depth_m * 1e3, fit.linear ? " (top of its range: linear)" : "",
            settings.pad_stiffening_depth_m * 1e3, fit.weight_scale, 100.0 * fit.rms_relative_error,
            100.0 * fit.max_relative_error);
        for (const auto& point : fit.points) {
            std::printf("| %.2f | %.3f | %.3f |\n", point.depth_m * 1e3, point.fem_force_n,
                        point.model_force_n);
        }
        std::printf("\n");
        const double indentation = indentation_mm * 1e-3;
        const double stiffness = haptic::tactile::femSecantStiffness(
            finger, indentation, device.thimble().plate_radius_m);
        const auto results = haptic::tactile::runFemErrorAnalysis(
            kinematics, settings, finger, haptic::tactile::femStandardCases(indentation),
            stiffness);

        std::ostringstream table;
        std::ostringstream data;
        table << "| case | F_v (N) | ‖M_v‖/‖F_v‖ | optimiser, cold | optimiser, warm | "
                 "plane fit | force-normal | cold solve | warm solve |\n"
                 "|---|---|---|---|---|---|---|---|---|\n";
        data << "# index name cold warm plane_fit force_normal (force error, percent)\n";
        int index = 0;
        for (const auto& r : results) {
            const double fv = r.reference.force_on_finger_n.norm();
            char head[128];
            std::snprintf(head, sizeof head, "| %s | %.3f | %.2f mm |", r.name.c_str(), fv,
                          1e3 * r.reference.moment_nm.norm() / fv);
            table << head << cell(r.cold) << cell(r.warm) << cell(r.plane_fit)
                  << cell(r.force_normal) << ' ' << report(r.cold_report) << " | "
                  << report(r.warm_report) << " |\n";
            const auto pct = [](const FemMethodResult& m) {
                return m.valid ? 100.0 * m.force_error : NAN;
            };
            data << index++ << " \"" << r.name << "\" " << pct(r.cold) << ' ' << pct(r.warm) << ' '
                 << pct(r.plane_fit) << ' ' << pct(r.force_normal) << '\n';
        }
        table << "\nCells: force error |F_d - F_v| / |F_v| (signed magnitude error; moment error "
                 "|M_d - M_v| / |F_v|, the centre of pressure's offset, moments about the "
                 "undeformed pad's lowest point). FEM fingertip level "
              << resolution << ", bone held, every contact " << indentation_mm
              << " mm into the undeformed pad; the plate is a square of 2 plate radii. "
                 "Force-normal baseline's finger stiffness: "
              << stiffness << " N/m (the FEM's secant for the flat plate at that depth).\n";
        std::printf("%s", table.str().c_str());
        std::filesystem::create_directories(out_dir);
        std::ofstream(std::filesystem::path(out_dir) / "fem_error_analysis.dat") << data.str();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "tactile_fem_error_analysis: %s\n", e.what());
        return 1;
    }
    return 0;
}
