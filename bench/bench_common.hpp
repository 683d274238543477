// bench_common.hpp: what the benchmark programs share: medians, number formatting, CSV text fields and
// files, aligned Markdown tables, the machine's name, option lists and progress lines on stderr.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "rcx/image.hpp"

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

// A Markdown table whose columns are padded to one width, so it reads as well on a terminal as rendered.
inline std::string markdown_table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows) {
    std::vector<std::size_t> width(header.size(), 3);
    for (std::size_t c = 0; c < header.size(); ++c) width[c] = std::max(width[c], header[c].size());
    for (const auto& row : rows)
        for (std::size_t c = 0; c < row.size() && c < width.size(); ++c) width[c] = std::max(width[c], row[c].size());
    std::string out;
    auto line = [&](const std::vector<std::string>& cells) {
        for (std::size_t c = 0; c < width.size(); ++c) {
            const std::string cell = c < cells.size() ? cells[c] : "";
            out += "| " + cell + std::string(width[c] - cell.size(), ' ') + " ";
        }
        out += "|\n";
    };
    line(header);
    for (std::size_t c = 0; c < width.size(); ++c) out += "|" + std::string(width[c] + 2, '-');
    out += "|\n";
    for (const auto& row : rows) line(row);
    return out;
}

// Where a benchmark writes its files: CSV files with their header line, and PNG images.
struct Report {
    std::ostringstream md;
    std::string dir;
    std::ofstream csv(const std::string& name, const std::string& header) const {
        std::ofstream f(dir + "/" + name);
        if (!f) throw std::runtime_error("cannot write " + dir + "/" + name);
        f << header << "\n";
        return f;
    }
    void png(const std::string& name, const Image& image) const { write_png(dir + "/" + name, image); }
};

inline std::string machine_name() {
    std::ifstream cpuinfo("/proc/cpuinfo");
    std::string line;
    while (std::getline(cpuinfo, line))
        if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
    return "unknown CPU";
}

// The options every benchmark program takes: --quick (small images, one round), --out DIR, --rounds N,
// --ns LIST (the behind-N rows; empty: the program's default).
struct CommonOptions {
    bool quick = false;
    std::string out = "docs/results";
    int rounds = 1;
    std::vector<int> ns;
};

// "a,b,c" -> {"a", "b", "c"}.
inline std::vector<std::string> split_list(const std::string& text) {
    std::vector<std::string> items;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ',')) items.push_back(item);
    return items;
}

inline std::vector<int> parse_list(const std::string& text) {
    std::vector<int> values;
    for (const std::string& item : split_list(text)) values.push_back(std::atoi(item.c_str()));
    return values;
}

// Takes argv[i] (and its value, advancing i) when it is one of the common options; false otherwise.
inline bool parse_common_option(int argc, char** argv, int& i, CommonOptions& o) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--quick") {
        o.quick = true;
        o.rounds = 1;
    } else if (a == "--out" && has_value) {
        o.out = argv[++i];
    } else if (a == "--rounds" && has_value) {
        o.rounds = std::max(1, std::atoi(argv[++i]));
    } else if (a == "--ns" && has_value) {
        o.ns = parse_list(argv[++i]);
    } else {
        return false;
    }
    return true;
}

inline void progress(const std::string& what) {
    std::fprintf(stderr, "[bench] %s\n", what.c_str());
    std::fflush(stderr);
}

} // namespace rcx::bench
