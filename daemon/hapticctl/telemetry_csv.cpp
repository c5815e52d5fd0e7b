#include "telemetry_csv.hpp"

#include <fmt/format.h>

#include "haptic/msgs/names.hpp"

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
    std::string header = "tick,time_s,device,device_kind,actuator_force_cmd_n";
    for (std::size_t i = 0; i < msgs::kThimbleServos; ++i) {
        header += fmt::format(",servo_angle_cmd_{}_rad", i);
    }
    return header + ",tick_work_us,wakeup_latency_us,read_us,write_us\n";
}

std::string telemetryCsvRow(const msgs::TelemetrySample& sample, std::int64_t origin_ns) {
    std::string row =
        fmt::format("{},{:.6f},{},{},{:.4f}", sample.tick,
                    static_cast<double>(sample.stamp_ns - origin_ns) * 1e-9, sample.device_index,
                    msgs::toString(sample.device_kind), sample.exoskeleton.actuator_force_cmd_n);
    for (const double angle : sample.thimble.servo_angle_cmd_rad) {
        row += fmt::format(",{:.4f}", angle);
    }
    return row + fmt::format(",{:.2f},{:.2f},{:.2f},{:.2f}\n", sample.tick_work_us,
                             sample.wakeup_latency_us, sample.read_us, sample.write_us);
}

std::string telemetryPlotScript(const std::string& csv_path, const std::string& png_path) {
    // Columns: 1 tick, 2 time, 3 device, 4 device kind, 5 exoskeleton force command [N],
    // 6-8 thimble servo commands [rad], 9 tick work (read + compute + write), 10 wake-up
    // latency, 11 read, 12 write. One panel per device kind, each in its own unit.
    const std::string csv = quoted(csv_path);
    std::string script = fmt::format(
        "set terminal pngcairo size 1200,1200 noenhanced\n"
        "set output {png}\n"
        "set datafile separator ','\n"
        "set multiplot layout 3,1 title {title}\n"
        "set grid\n"
        "set xlabel 'time [s]'\n",
        fmt::arg("png", quoted(png_path)),
        fmt::arg("title", quoted("hapticd telemetry: " + csv_path)));
    script += fmt::format(
        "set ylabel 'exoskeleton actuator force command [N]'\n"
        "plot {csv} every ::1 using (strcol(4) eq 'exoskeleton' ? $2 : 1/0):5 with points pt 7 "
        "ps 0.3 title 'actuator force'\n",
        fmt::arg("csv", csv));
    script += "set ylabel 'thimble servo angle command [rad]'\nplot ";
    for (int servo = 0; servo < 3; ++servo) {
        script += fmt::format(
            "{sep}{csv} every ::1 using (strcol(4) eq 'thimble' ? $2 : 1/0):{column} with points "
            "pt 7 ps 0.3 title 'servo {servo}'",
            fmt::arg("sep", servo == 0 ? "" : ", "), fmt::arg("csv", csv),
            fmt::arg("column", 6 + servo), fmt::arg("servo", servo));
    }
    script += "\n";
    script += fmt::format(
        "set ylabel 'loop timing [us, log scale]'\n"
        "set logscale y\n"
        "plot {csv} every ::1 using ($3==0 ? $2 : 1/0):9 with points pt 7 ps 0.3 title 'tick "
        "work (read+compute+write)', "
        "{csv} every ::1 using ($3==0 ? $2 : 1/0):11 with points pt 7 ps 0.3 title 'read', "
        "{csv} every ::1 using ($3==0 ? $2 : 1/0):12 with points pt 7 ps 0.3 title 'write', "
        "{csv} every ::1 using ($3==0 ? $2 : 1/0):10 with points pt 7 ps 0.3 title 'wake-up "
        "latency'\n"
        "unset multiplot\n",
        fmt::arg("csv", csv));
    return script;
}

}  // namespace haptic::ctl
