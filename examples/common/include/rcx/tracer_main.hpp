// tracer_main.hpp: what every example tracer's main() does around its own work: the program's name, the
// command line parsed (bad options: message, exit status 2), --help printed (exit 0), the run, and its
// exceptions turned into exit statuses (InputError: 2; any other std::exception: "error:", 1).
#pragma once

#include <functional>
#include <stdexcept>
#include <string>

#include "rcx/options.hpp"

namespace rcx {

// Bad input found while running (an unreadable scene, a cache file, more memory than is available):
// message on stderr, exit status 2.
struct InputError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// argv[0]'s file name, or `fallback` when there is none.
std::string program_name(int argc, char** argv, const char* fallback);

// parse() (UsageError: "<program>: <message>" on stderr, 2), then each of the options' notes as
// "<program>: note: <note>" on stderr; with --help, help() on stdout and 0;
// otherwise run(options), with InputError reported as "<program>: <message>" and 2, any other
// std::exception as "<program>: error: <message>" and 1.
int tracer_main(const std::string& program, const std::function<Options()>& parse,
                const std::function<std::string()>& help, const std::function<int(const Options&)>& run);

} // namespace rcx
