// rcx/command_line.hpp: the example tracers' command line. CLI11 (Debian: libcli11-dev) matches the
// options, their values ("--name value", "--name=value") and lays out --help in sections; the values are
// checked by rcx/option_values.hpp, and CLI11's errors are rephrased as UsageError naming the option.
// A tracer with options of its own declares them here beside the shared ones (rcx::Options), so they
// parse and appear in --help the same way. CLI11 stays inside src/command_line.cpp.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "rcx/options.hpp"

namespace CLI {
class App;
}

namespace rcx {

class CommandLine {
public:
    // Declares the shared options; `program` (argv[0]'s file name) opens the usage line of --help.
    explicit CommandLine(const std::string& program);
    ~CommandLine();
    CommandLine(const CommandLine&) = delete; // CLI11 holds callbacks into this object
    CommandLine& operator=(const CommandLine&) = delete;

    // Options declared from now on appear under `heading` in --help.
    void section(const std::string& heading);
    // An option taking a value. `names`: "--name" (or "-n,--name"); `value`: how --help names the value
    // ("N", "FILE"); `store` checks the text and keeps it, throwing UsageError naming the option.
    void add_option(const std::string& names, const std::string& value, const std::string& description,
                    std::function<void(const std::string& text)> store);
    // An option without a value: present sets `target`; "--name=anything" is refused.
    void add_flag(const std::string& names, bool& target, const std::string& description);
    // A paragraph for the end of --help, before the closing lines on value syntax and exit status.
    void add_note(const std::string& paragraph);
    // For a tracer whose threads are not its own to choose: --threads still parses, and parse() notes
    // "--threads has no effect: <why>" when it is given, instead of fitting it to the machine's cores.
    void ignore_threads(const std::string& why);

    // Parses argv[1..argc-1]: each option is applied in command-line order, so a repeated option's last
    // value wins. Throws UsageError naming the option (or argument) at fault. Call once.
    Options parse(int argc, const char* const argv[]);
    // The --help text: every option declared, by section, with defaults in brackets.
    std::string help() const;

private:
    std::unique_ptr<CLI::App> app_;
    Options options_;
    bool no_pyramid_ = false; // --no-pyramid, a flag that clears Options::pyramid
    std::string section_;
    std::string notes_;
    std::string threads_ignored_; // why --threads has no effect (ignore_threads()); empty: it has
};

// "[value]": how --help shows a default. Floats in their shortest form (0.1, not 0.100000).
std::string shown_default(const std::string& value);
std::string shown_default(float value);

} // namespace rcx
