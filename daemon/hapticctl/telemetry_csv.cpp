#include "telemetry_csv.hpp"

#include <fmt/format.h>

namespace haptic::ctl {
namespace {
// Quotes a path for a gnuplot single-quoted string (a quote is written twice).
std::string quoted(const std::string& path) {
    std::string out = "'";
    for (const char c : path) {
        out += c;
        if (c == '\'') {
            out += '\'';
        }
    }
    return out + "'";
}
}  // namespace

std::string telemetryCsvHeader() {
    std::string header = "tick,time_s,device";
    for (std::size_t i = 0; i < msgs::kMaxActuators; ++i) {
        header += fmt::format(",force_cmd_{}_n", i);
    }
    return header + ",compute_us,wakeup_latency_us\n";
}

std::string telemetryCsvRow(const msgs::TelemetrySample& sample, std::int64_t origin_ns) {
    std::string row =
        fmt::format("{},{:.6f},{}", sample.tick,
                    static_cast<double>(sample.stamp_ns - origin_ns) * 1e-9, sample.device_index);
    for (const double force : sample.actuator_force_cmd) {
        row += fmt::format(",{:.4f}", force);
    }
    return row + fmt::format(",{:.2f},{:.2f}\n", sample.compute_us, sample.wakeup_latency_us);
}

std::string telemetryPlotScript(const std::string& csv_path, const std::string& png_path) {
    // Columns: 1 tick, 2 time, 3 device, 4-7 forces, 8 compute, 9 wake-up latency.
    const std::string csv = quoted(csv_path);
    return fmt::format(
        "set terminal pngcairo size 1200,900 noenhanced\n"
        "set output {png}\n"
        "set datafile separator ','\n"
        "set multiplot layout 2,1 title {title}\n"
        "set grid\n"
        "set xlabel 'time [s]'\n"
        "set ylabel 'commanded force [N]'\n"
        "plot {csv} every ::1 using ($3==0 ? $2 : 1/0):4 with points pt 7 ps 0.3 title 'device 0 "
        "actuator 0', "
        "{csv} every ::1 using ($3==1 ? $2 : 1/0):4 with points pt 7 ps 0.3 title 'device 1 "
        "actuator 0'\n"
        "set ylabel 'loop timing [us]'\n"
        "plot {csv} every ::1 using ($3==0 ? $2 : 1/0):8 with points pt 7 ps 0.3 title 'compute "
        "(read+compute+write)', "
        "{csv} every ::1 using ($3==0 ? $2 : 1/0):9 with points pt 7 ps 0.3 title 'wake-up "
        "latency'\n"
        "unset multiplot\n",
        fmt::arg("png", quoted(png_path)), fmt::arg("csv", csv),
        fmt::arg("title", quoted("hapticd telemetry: " + csv_path)));
}

}  // namespace haptic::ctl
