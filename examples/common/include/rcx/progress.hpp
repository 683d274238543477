// rcx/progress.hpp: a one-line progress bar on stderr for long runs. Draws only when enabled (see
// progress_enabled); redraws at most ~10 times a second. Not thread-safe: call from one thread.
#pragma once

#include <chrono>
#include <string>

namespace rcx {

// True when a bar should be drawn: never when quiet, always when forced, else when stderr is a terminal.
bool progress_enabled(bool quiet, bool forced);

class ProgressBar {
public:
    ProgressBar(std::string label, int total, bool enabled);
    ~ProgressBar();                   // finish()
    ProgressBar(const ProgressBar&) = delete;
    ProgressBar& operator=(const ProgressBar&) = delete;

    void advance(int steps = 1);      // done += steps, redraw when due
    void clear();                     // erase the bar's line, so the caller can print; the next advance redraws
    void finish();                    // draw the full bar and end its line (once)
    bool enabled() const { return enabled_; }

private:
    void draw(bool force);
    std::string label_;
    int total_;
    int done_ = 0;
    int drawn_ = -1; // done_ when last drawn
    bool enabled_;
    bool finished_ = false;
    std::chrono::steady_clock::time_point start_, last_draw_;
};

} // namespace rcx
