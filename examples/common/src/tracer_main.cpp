// The example tracers' main() wrapper; see rcx/tracer_main.hpp.
#include "rcx/tracer_main.hpp"

#include <cstdio>
#include <exception>
#include <filesystem>

namespace rcx {

std::string program_name(int argc, char** argv, const char* fallback) {
    return std::filesystem::path(argc > 0 ? argv[0] : fallback).filename().string();
}

int tracer_main(const std::string& program, const std::function<Options()>& parse,
                const std::function<std::string()>& help, const std::function<int(const Options&)>& run) {
    Options options;
    try {
        options = parse();
    } catch (const UsageError& e) {
        std::fprintf(stderr, "%s: %s\n", program.c_str(), e.what());
        return 2;
    }
    for (const std::string& note : options.notes) std::fprintf(stderr, "%s: note: %s\n", program.c_str(), note.c_str());
    if (options.help) {
        std::fputs(help().c_str(), stdout);
        return 0;
    }
    try {
        return run(options);
    } catch (const InputError& e) {
        std::fprintf(stderr, "%s: %s\n", program.c_str(), e.what());
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s: error: %s\n", program.c_str(), e.what());
        return 1;
    }
}

} // namespace rcx
