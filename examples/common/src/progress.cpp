// The progress bar.
#include "rcx/progress.hpp"

#include <algorithm>
#include <cstdio>

#include <unistd.h>

namespace rcx {

bool progress_enabled(bool quiet, bool forced) {
    if (quiet) return false;
    return forced || isatty(STDERR_FILENO) == 1;
}

ProgressBar::ProgressBar(std::string label, int total, bool enabled)
    : label_(std::move(label)), total_(std::max(total, 1)), enabled_(enabled),
      start_(std::chrono::steady_clock::now()), last_draw_() {}

ProgressBar::~ProgressBar() { finish(); }

void ProgressBar::advance(int steps) {
    done_ = std::min(total_, done_ + steps);
    draw(false);
}

void ProgressBar::clear() {
    if (!enabled_ || finished_) return;
    std::fputs("\r\033[K", stderr);
    std::fflush(stderr);
    last_draw_ = {};
    drawn_ = -1;
}

void ProgressBar::finish() {
    if (finished_) return;
    if (enabled_) {
        done_ = total_;
        if (drawn_ != done_) draw(true);
        std::fputc('\n', stderr);
        std::fflush(stderr);
    }
    finished_ = true;
}

void ProgressBar::draw(bool force) {
    if (!enabled_ || finished_) return;
    const auto now = std::chrono::steady_clock::now();
    if (!force && done_ < total_ && now - last_draw_ < std::chrono::milliseconds(100)) return;
    last_draw_ = now;
    drawn_ = done_;
    constexpr int width = 30;
    const int filled = static_cast<int>(static_cast<long long>(width) * done_ / total_);
    const double seconds = std::chrono::duration<double>(now - start_).count();
    const double eta = done_ > 0 ? seconds * (total_ - done_) / done_ : 0.0;
    std::fprintf(stderr, "\r\033[K%s [%.*s%*s] %d/%d  %.1fs, ~%.0fs left", label_.c_str(), filled,
                 "##############################", width - filled, "", done_, total_, seconds, eta);
    std::fflush(stderr);
}

} // namespace rcx
