// Reproduces the synthetic chapter 6 study (docs/algorithms.md §6.10): sweeps over rho, wall angle
// beta and k_a/k_u (quasi-static equilibria solved through the real renderer), a dynamic slide
// along the wall, and energy pumping with the passivity controller on and off. Writes CSV files
// and, unless --no-plots, PNG plots through gnuplot. Exits non-zero if a numeric equilibrium
// disagrees with the closed forms of §6.6 or the best match fails, so it doubles as a test.
//
//   kinesthetic_study --out daemon/kinesthetic/study/results            # full study, ~10 s
//   kinesthetic_study --out /tmp/study --quick --no-plots          # what ctest runs

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "haptic/kinesthetic/anisotropic.hpp"
#include "haptic/kinesthetic/study.hpp"

namespace {

using namespace haptic::kinesthetic;
namespace fs = std::filesystem;

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kInf = std::numeric_limits<double>::infinity();

int g_failures = 0;

void check(bool ok, const std::string& what) {
    if (!ok) {
        ++g_failures;
        std::cerr << "kinesthetic_study: CHECK FAILED: " << what << "\n";
    }
}

void compare(const study::WallMeasurement& m, const SingleWallPrediction& p,
             const std::string& label) {
    const double tolerance = 1e-7 * (1.0 + p.full_force);
    check(m.converged, label + ": equilibrium did not converge");
    check(std::abs(m.ghost_force - p.ghost_force) < tolerance,
          label + ": ghost " + std::to_string(m.ghost_force) + " vs closed form " +
              std::to_string(p.ghost_force));
    check(std::abs(m.normal_force - p.normal_force) < tolerance, label + ": normal force");
    check(std::abs(m.force_error - p.force_error) < tolerance, label + ": force error");
}

struct Strategy {
    const char* name;
    RenderingMethod method;
    RhoMode mode;
    double rho;  // for the closed-form comparison; NaN = rho*
};

const Strategy kStrategies[] = {
    {"naive", RenderingMethod::kNaive, RhoMode::kManual, 1.0},
    {"subspace", RenderingMethod::kSubspace, RhoMode::kManual, kInf},
    {"anisotropic", RenderingMethod::kAnisotropic, RhoMode::kClosedForm,
     std::numeric_limits<double>::quiet_NaN()},
};

// Manual rho for the renderer (only the anisotropic strategy reads it).
double overrideOf(const Strategy& s) {
    return std::isfinite(s.rho) ? s.rho : 1.0;
}

void rhoSweep(const fs::path& out, bool quick) {
    std::ofstream csv(out / "rho_sweep.csv");
    csv << "beta_deg,rho,full_force_n,rendered_force_n,normal_force_n,tangential_force_n,"
           "ghost_force_n,force_error_n,ghost_closed_form_n\n";
    const int points = quick ? 7 : 61;
    for (const double beta_deg : {15.0, 30.0, 45.0, 60.0, 75.0}) {
        study::WallCase wall;
        wall.beta_rad = beta_deg * kDeg;
        for (int i = 0; i < points; ++i) {
            const double rho = std::pow(10.0, -3.0 + 6.0 * i / (points - 1));
            const auto m =
                study::measureWall(wall, RenderingMethod::kAnisotropic, RhoMode::kManual, rho);
            const auto p =
                predictSingleWall(wall.k_a, wall.k_u, wall.depth_u_m, std::cos(wall.beta_rad), rho);
            compare(m, p, "rho sweep beta " + std::to_string(beta_deg));
            csv << beta_deg << ',' << rho << ',' << m.full_force << ',' << m.rendered_force << ','
                << m.normal_force << ',' << m.tangential_force << ',' << m.ghost_force << ','
                << m.force_error << ',' << p.ghost_force << '\n';
        }
    }
}

void betaSweep(const fs::path& out, bool quick) {
    std::ofstream csv(out / "beta_sweep.csv");
    csv << "beta_deg,full_force_n";
    for (const auto& s : kStrategies) {
        csv << ",ghost_" << s.name << ",normal_" << s.name << ",tangential_" << s.name << ",error_"
            << s.name;
    }
    csv << '\n';
    const double step = quick ? 20.0 : 2.5;
    for (double beta_deg = 0.0; beta_deg <= 85.0 + 1e-9; beta_deg += step) {
        study::WallCase wall;
        wall.beta_rad = beta_deg * kDeg;
        csv << beta_deg;
        bool first = true;
        for (const auto& s : kStrategies) {
            const auto m = study::measureWall(wall, s.method, s.mode, overrideOf(s));
            const double rho = std::isnan(s.rho) ? optimalRhoIsotropic(wall.k_a, wall.k_u) : s.rho;
            compare(
                m,
                predictSingleWall(wall.k_a, wall.k_u, wall.depth_u_m, std::cos(wall.beta_rad), rho),
                std::string("beta sweep ") + s.name);
            if (first) {
                csv << ',' << m.full_force;
                first = false;
            }
            csv << ',' << m.ghost_force << ',' << m.normal_force << ',' << m.tangential_force << ','
                << m.force_error;
            if (std::isnan(s.rho)) {
                check(m.ghost_force <= 1e-9 * m.full_force, "best match at rho*");
            }
        }
        csv << '\n';
    }
}

void ratioSweep(const fs::path& out, bool quick) {
    std::ofstream csv(out / "ratio_sweep.csv");
    csv << "ka_over_ku,rho_star,full_force_n";
    for (const auto& s : kStrategies) {
        csv << ",ghost_" << s.name << ",error_" << s.name;
    }
    csv << '\n';
    const int points = quick ? 4 : 25;
    for (int i = 0; i < points; ++i) {
        study::WallCase wall;
        wall.beta_rad = 45.0 * kDeg;
        const double ratio = std::pow(10.0, -1.0 + 2.5 * i / (points - 1));
        wall.k_a = ratio * wall.k_u;
        csv << ratio << ',' << optimalRhoIsotropic(wall.k_a, wall.k_u);
        bool first = true;
        for (const auto& s : kStrategies) {
            const auto m = study::measureWall(wall, s.method, s.mode, overrideOf(s));
            if (first) {
                csv << ',' << m.full_force;
                first = false;
            }
            csv << ',' << m.ghost_force << ',' << m.force_error;
        }
        csv << '\n';
    }
}

void slide(const fs::path& out, bool quick) {
    std::ofstream summary(out / "slide_summary.csv");
    summary << "beta_deg,strategy,rms_ghost_force_n,rms_tangential_drift_m,mean_normal_force_n\n";
    std::ofstream series(out / "slide_timeseries.csv");
    series << "time_s";
    for (const auto& s : kStrategies) {
        series << ",ghost_" << s.name << ",drift_" << s.name;
    }
    series << '\n';
    for (const double beta_deg : {30.0, 45.0, 60.0}) {
        study::SlideCase slide_case;
        slide_case.wall.beta_rad = beta_deg * kDeg;
        slide_case.duration_s = quick ? 0.3 : 2.0;
        std::vector<study::SlideResult> results;
        for (const auto& s : kStrategies) {
            results.push_back(study::simulateSlide(slide_case, s.method, s.mode, overrideOf(s)));
            const auto& r = results.back();
            summary << beta_deg << ',' << s.name << ',' << r.rms_ghost_force << ','
                    << r.rms_tangential_drift << ',' << r.mean_normal_force << '\n';
        }
        check(
            results[2].rms_ghost_force < results[0].rms_ghost_force &&
                results[0].rms_ghost_force < results[1].rms_ghost_force,
            "slide: RMS ghost anisotropic < naive < subspace at beta " + std::to_string(beta_deg));
        if (beta_deg == 45.0) {
            for (std::size_t k = 0; k < results[0].time_s.size(); k += 5) {
                series << results[0].time_s[k];
                for (const auto& r : results) {
                    series << ',' << r.ghost_force[k] << ',' << r.tangential_drift[k];
                }
                series << '\n';
            }
        }
    }
}

void pumping(const fs::path& out, bool quick) {
    std::ofstream summary(out / "pumping_summary.csv");
    summary << "strategy,beta_deg,generated_energy_pc_off_j,generated_energy_pc_on_j,"
               "max_force_pc_off_n,max_force_pc_on_n\n";
    std::ofstream series(out / "pumping_timeseries.csv");
    series << "time_s,energy_naive_pc_off_j,energy_naive_pc_on_j,energy_anisotropic_pc_off_j,"
              "energy_anisotropic_pc_on_j\n";
    study::PumpingCase pumping_case;
    pumping_case.cycles = quick ? 1 : 5;
    std::vector<study::PumpingResult> series_runs;
    const std::vector<double> pumping_angles =
        quick ? std::vector<double>{45.0} : std::vector<double>{30.0, 45.0, 60.0};
    for (const double beta_deg : pumping_angles) {
        pumping_case.wall.beta_rad = beta_deg * kDeg;
        for (const auto& s : kStrategies) {
            const auto off =
                study::runEnergyPumping(pumping_case, s.method, s.mode, overrideOf(s), false);
            const auto on =
                study::runEnergyPumping(pumping_case, s.method, s.mode, overrideOf(s), true);
            summary << s.name << ',' << beta_deg << ',' << off.generated_energy_j << ','
                    << on.generated_energy_j << ',' << off.max_force_n << ',' << on.max_force_n
                    << '\n';
            check(off.generated_energy_j > 0.0, "pumping generates energy without the PC");
            check(on.generated_energy_j <= 0.0, "no net energy generated with the PC on");
            if (beta_deg == 45.0 && s.method != RenderingMethod::kSubspace) {
                series_runs.push_back(off);
                series_runs.push_back(on);
            }
        }
    }
    for (std::size_t k = 0; k < series_runs[0].time_s.size(); k += 5) {
        series << series_runs[0].time_s[k];
        for (const auto& r : series_runs) {
            series << ',' << r.generated_energy[k];
        }
        series << '\n';
    }
}

const char* kGnuplotScript = R"(
set datafile separator ','
set key autotitle columnhead
set terminal pngcairo size 900,600 font ',11'
set grid

set output 'ghost_vs_rho.png'
set logscale x
set xlabel 'anisotropy rho = k_{nonact} / k_a'
set ylabel 'ghost force |f_r - P_a F_full| (N)'
set title 'Ghost force vs rho (k_a = 1000 N/m, k_u = 300 N/m, intent 10 mm inside); rho* = 0.231'
set arrow 1 from 0.2308,graph 0 to 0.2308,graph 1 nohead dt 2
plot for [b in '15 30 45 60 75'] 'rho_sweep.csv' using 2:($1==b+0 ? $7 : 1/0) with lines lw 2 title 'beta = '.b.' deg'

set output 'normal_error_vs_rho.png'
set multiplot layout 1,2
set ylabel 'normal force (N)'
set title 'Normal force vs rho'
plot for [b in '15 30 45 60 75'] 'rho_sweep.csv' using 2:($1==b+0 ? $5 : 1/0) with lines lw 2 title 'beta = '.b
set ylabel '|f_r - F_full| (N)'
set title 'Force error vs rho'
plot for [b in '15 30 45 60 75'] 'rho_sweep.csv' using 2:($1==b+0 ? $8 : 1/0) with lines lw 2 title 'beta = '.b
unset multiplot
unset arrow 1
unset logscale x

set output 'forces_vs_beta.png'
set terminal pngcairo size 1500,500 font ',11'
set multiplot layout 1,3
set xlabel 'wall angle beta (deg) between normal and actuated direction'
set ylabel 'ghost force (N)'
set title 'Ghost force'
plot 'beta_sweep.csv' using 1:3 w l lw 2 t 'naive (rho=1)', '' using 1:7 w l lw 2 t 'subspace (rho=inf)', '' using 1:11 w l lw 2 t 'anisotropic (rho*)'
set ylabel 'normal force (N)'
set title 'Normal force (fully actuated: 2.31 N)'
plot 'beta_sweep.csv' using 1:4 w l lw 2 t 'naive', '' using 1:8 w l lw 2 t 'subspace', '' using 1:12 w l lw 2 t 'anisotropic', '' using 1:2 w l dt 2 t 'fully actuated'
set ylabel '|f_r - F_full| (N)'
set title 'Force error'
plot 'beta_sweep.csv' using 1:6 w l lw 2 t 'naive', '' using 1:10 w l lw 2 t 'subspace', '' using 1:14 w l lw 2 t 'anisotropic'
unset multiplot

set terminal pngcairo size 900,600 font ',11'
set output 'ghost_vs_ratio.png'
set logscale x
set xlabel 'k_a / k_u'
set ylabel 'ghost force / |F_full|'
set title 'Ghost force vs stiffness ratio (beta = 45 deg)'
plot 'ratio_sweep.csv' using 1:($4/$3) w l lw 2 t 'naive', '' using 1:($6/$3) w l lw 2 t 'subspace', '' using 1:($8/$3) w l lw 2 t 'anisotropic (rho*)'
unset logscale x

set output 'pumping.png'
set xlabel 'time (s)'
set ylabel 'energy generated by the device (J)'
set title 'Closed loops inside the wall (beta = 45 deg, 2 Hz, 4 mm radius)'
plot 'pumping_timeseries.csv' using 1:2 w l lw 2 t 'naive, PC off', '' using 1:3 w l lw 2 t 'naive, PC on', '' using 1:4 w l lw 2 t 'anisotropic, PC off', '' using 1:5 w l lw 2 t 'anisotropic, PC on'
)";

int plot(const fs::path& out) {
    const fs::path script = out / "plots.gnuplot";
    {
        std::ofstream file(script);
        file << kGnuplotScript;
    }
    const std::string command = "cd '" + out.string() + "' && gnuplot plots.gnuplot";
    const int status = std::system(command.c_str());
    if (status != 0) {
        std::cerr << "kinesthetic_study: gnuplot failed (" << status
                  << "); is gnuplot-nox installed (scripts/install-deps.sh)?\n";
        return 1;
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{"Chapter 6 synthetic study: ghost forces, anisotropic coupling, pumping"};
    std::string out_dir = "kinesthetic_study";
    bool quick = false;
    bool no_plots = false;
    app.add_option("--out", out_dir, "Output folder for CSV and PNG files");
    app.add_flag("--quick", quick, "Coarse sweeps and short runs (for ctest)");
    app.add_flag("--no-plots", no_plots, "Write CSV only, do not run gnuplot");
    CLI11_PARSE(app, argc, argv);

    const fs::path out(out_dir);
    std::error_code error;
    fs::create_directories(out, error);
    if (error) {
        std::cerr << "kinesthetic_study: cannot create " << out << ": " << error.message() << "\n";
        return 2;
    }
    rhoSweep(out, quick);
    betaSweep(out, quick);
    ratioSweep(out, quick);
    slide(out, quick);
    pumping(out, quick);
    if (!no_plots && plot(out) != 0) {
        return 1;
    }
    if (g_failures > 0) {
        std::cerr << "kinesthetic_study: " << g_failures << " check(s) failed\n";
        return 1;
    }
    std::cout << "kinesthetic_study: wrote " << out << "\n";
    return 0;
}
