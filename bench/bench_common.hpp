// bench_common.hpp: what the benchmark programs share: medians, number formatting, CSV text fields, the
// machine's name and progress lines on stderr.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

namespace rcx::bench {

inline double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v.empty() ? 0.0 : v[v.size() / 2];
}

inline std::string fmt(double value, int digits = 2) {
    if (std::isinf(value)) return "inf";
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%.*f", digits, value);
    return buffer;
}

// A CSV text field: quoted, so labels may contain commas.
inline std::string csv_text(const std::string& text) { return "\"" + text + "\""; }

inline std::string machine_name() {
    std::ifstream cpuinfo("/proc/cpuinfo");
    std::string line;
    while (std::getline(cpuinfo, line))
        if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
    return "unknown CPU";
}

inline void progress(const std::string& what) {
    std::fprintf(stderr, "[bench] %s\n", what.c_str());
    std::fflush(stderr);
}

} // namespace rcx::bench
