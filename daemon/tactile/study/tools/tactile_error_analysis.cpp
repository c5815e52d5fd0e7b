// Error analysis of thimble rendering methods (docs/algorithms.md §3.7): for each virtual contact,
// compare the force the device plate would press into the fingertip model with the force of
// the virtual contact, for the contact optimiser and the two baselines.
//
//   tactile_error_analysis [--config config/devices/thimble.yaml] [--out DIR]
//
// Prints the markdown table that docs/benchmarks.md records (the project's one results file)
// and writes DIR/error_analysis.dat, the gnuplot input that error_analysis.gp renders.

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
#include "haptic/tactile/error_analysis.hpp"

namespace {

using haptic::tactile::ForceComparison;
using haptic::tactile::NonlinearPadModel;
using haptic::tactile::ThimbleKinematics;

constexpr double kIndentationM = 0.0015;  // depth of every virtual contact past first touch

std::string cell(const ForceComparison& m) {
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
    CLI::App app{"Force-error analysis of thimble rendering methods (docs/algorithms.md §3.7)"};
    std::string config_path = HAPTIC_DEFAULT_THIMBLE_CONFIG;
    std::string out_dir = ".";
    app.add_option("--config", config_path, "thimble device YAML")->check(CLI::ExistingFile);
    app.add_option("--out", out_dir, "folder for error_analysis.dat (the gnuplot input)");
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
        // This analysis's reference is the stand-in pad model, and the optimiser is given that
        // model's law (the shipped one is fitted to the FEM: tactile_fem_error_analysis is the
        // independent analysis): it checks the optimiser's fit on a pad it models exactly.
        settings.pad_stiffening_depth_m = pad_parameters.stiffening_depth_m;
        haptic::tactile::ContactSurfaceOptimiser optimiser(kinematics, settings);
        int samples = device.thimble().optimiser.pad_samples;
        if (sample_override > 0) {
            samples = sample_override;
        }
        const auto weighting = weighting_name == "area" ? haptic::tactile::SampleWeighting::kArea
                               : weighting_name == "force"
                                   ? haptic::tactile::SampleWeighting::kContactForce
                                   : haptic::tactile::SampleWeighting::kContactStiffness;

        const auto results = haptic::tactile::runErrorAnalysis(
            kinematics, pad, optimiser,
            haptic::tactile::standardCases(pad.parameters(), kIndentationM),
            {samples, weighting, stiffness});

        std::ostringstream table;
        std::ostringstream data;
        table << "| case | reachable | F_v (N) | optimiser | geometric plane | force-normal | "
                 "optimiser report |\n|---|---|---|---|---|---|---|\n";
        data << "# index name optimiser_error geometric_error force_error (percent)\n";
        int index = 0;
        for (const auto& c : results) {
            const auto& r = c.optimiser_report;
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
            char force[32];
            std::snprintf(force, sizeof force, "%.3f", c.virtual_force_n);
            table << "| " << c.name << " | " << (c.reachable() ? "yes" : "no") << " | " << force
                  << " |" << cell(c.optimiser) << cell(c.geometric) << cell(c.force_normal) << " "
                  << report << " |\n";
            auto pct = [](const ForceComparison& m) {
                return m.valid ? 100.0 * m.force_error : NAN;
            };
            data << index++ << " \"" << c.name << "\" " << pct(c.optimiser) << ' '
                 << pct(c.geometric) << ' ' << pct(c.force_normal) << '\n';
        }
        table << "\nCells: force error |F_d - F_v| / |F_v| (signed magnitude error, direction "
                 "error, Jaccard overlap of the contact node sets). Finger stiffness for the "
                 "force-normal baseline: "
              << stiffness << " N/m (secant at " << kIndentationM * 1e3
              << " mm). Pad model: " << pad.nodeCount() << " nodes; optimiser input: " << samples
              << " samples.\n";
        std::printf("%s", table.str().c_str());
        std::filesystem::create_directories(out_dir);
        std::ofstream(std::filesystem::path(out_dir) / "error_analysis.dat") << data.str();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "tactile_error_analysis: %s\n", e.what());
        return 1;
    }
    return 0;
}
