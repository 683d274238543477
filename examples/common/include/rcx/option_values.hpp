// rcx/option_values.hpp: the text of one option's value turned into a checked number or size. Each
// function throws UsageError naming `option` and the text, so a user knows what to change. CLI11 matches
// the options (rcx/command_line.hpp); these are stricter than its own conversions, which take hex
// ("0x10"), NaN, infinities and subnormal floats.
#pragma once

#include <string>

namespace rcx {

// A decimal integer in [min, max].
long parse_int_value(const std::string& option, const std::string& text, long min, long max);

// A finite float, 0 or of normal size (subnormals are refused: too small to compute with); `positive`
// additionally requires > 0.
float parse_float_value(const std::string& option, const std::string& text, bool positive);

struct ImageSize {
    int width = 0;
    int height = 0;
};
// "WxH" (or "WXH"), each side 1..max_image_side.
constexpr long max_image_side = 16384;
ImageSize parse_image_size(const std::string& option, const std::string& text);

} // namespace rcx
