// Checked conversions of option values (rcx/option_values.hpp).
#include "rcx/option_values.hpp"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include "rcx/options.hpp"

namespace rcx {

namespace {
// strtol and strtof pass over leading white space; a value with it is refused, as one with trailing space is.
bool starts_with_space(const std::string& text) { return !text.empty() && std::isspace(static_cast<unsigned char>(text[0])); }
} // namespace

long parse_int_value(const std::string& option, const std::string& text, long min, long max) {
    errno = 0;
    char* end = nullptr;
    const long v = std::strtol(text.c_str(), &end, 10);
    if (text.empty() || starts_with_space(text) || *end != '\0' || errno == ERANGE)
        throw UsageError(option + ": '" + text + "' is not an integer");
    if (v < min || v > max)
        throw UsageError(option + ": " + text + " is out of range " + std::to_string(min) + ".." + std::to_string(max));
    return v;
}

float parse_float_value(const std::string& option, const std::string& text, bool positive) {
    errno = 0;
    char* end = nullptr;
    const float v = std::strtof(text.c_str(), &end);
    const bool out_of_range = errno == ERANGE;
    if (text.empty() || starts_with_space(text) || end == text.c_str() || *end != '\0')
        throw UsageError(option + ": '" + text + "' is not a number");
    if (std::isnan(v) || (std::isinf(v) && !out_of_range))
        throw UsageError(option + ": '" + text + "' is not a finite number");
    auto shortest = [](float limit) {
        char digits[32];
        std::snprintf(digits, sizeof digits, "%g", static_cast<double>(limit));
        return std::string(digits);
    };
    if (std::isinf(v))
        throw UsageError(option + ": " + text + " is too large for a float (the largest is " +
                         shortest(std::numeric_limits<float>::max()) + ")");
    if (out_of_range || (v != 0.0f && !std::isnormal(v)))
        throw UsageError(option + ": " + text + " is too small: below the smallest normal float (" +
                         shortest(std::numeric_limits<float>::min()) + "), it would be a subnormal number or 0");
    if (positive && !(v > 0.0f)) throw UsageError(option + ": must be > 0, got " + text);
    return v;
}

ImageSize parse_image_size(const std::string& option, const std::string& text) {
    const std::size_t x = text.find_first_of("xX");
    if (x == std::string::npos)
        throw UsageError(option + ": '" + text + "' is not WIDTHxHEIGHT (for example 512x512)");
    return {static_cast<int>(parse_int_value(option + " (width)", text.substr(0, x), 1, max_image_side)),
            static_cast<int>(parse_int_value(option + " (height)", text.substr(x + 1), 1, max_image_side))};
}

} // namespace rcx
