// rcx/image.hpp: linear-RGB images, PNG output and image comparison (PSNR, errors, the thesis's
// blue-to-red difference image, Figure 5.4c).
//
// Tone map used everywhere (PNG and comparison): clamp to [0, 1], gamma 1/2.2, round to 8 bits.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

namespace rcx {

struct Image {
    int width = 0;
    int height = 0;
    std::vector<glm::vec3> pixels;    // linear RGB, row-major, row 0 at the top

    Image() = default;
    Image(int w, int h, glm::vec3 fill = glm::vec3(0.0f)); // throws std::invalid_argument for w or h < 0
    glm::vec3& at(int x, int y) { return pixels[static_cast<std::size_t>(y) * width + x]; }
    const glm::vec3& at(int x, int y) const { return pixels[static_cast<std::size_t>(y) * width + x]; }
};

// The 8-bit value a linear channel becomes: round(255 * clamp(v, 0, 1)^(1/2.2)); NaN becomes 0.
std::uint8_t tone_map(float linear);

// Writes an 8-bit RGB PNG (tone-mapped). Throws std::runtime_error with the path and the reason (for
// example a missing or unwritable folder) when it cannot write.
void write_png(const std::string& path, const Image& image);

// How far two images of the same size are apart, on their tone-mapped 8-bit values.
struct ImageDifference {
    double psnr_db = 0.0;             // 10 log10(255^2 / MSE) over all channels; +infinity when identical
    double mean_abs_error = 0.0;      // mean over all channels of |a - b| / 255 (0..1)
    double max_abs_error = 0.0;       // largest channel |a - b| / 255 (0..1)
    std::size_t differing_pixels = 0; // pixels with any channel different
    std::size_t pixels = 0;
};

// Throws std::invalid_argument when the sizes differ.
ImageDifference compare(const Image& a, const Image& b);

// True when both images have the same size and every pixel the same float bits (-0 differs from +0):
// stricter than compare(), which sees only the tone-mapped 8-bit values.
bool bit_identical(const Image& a, const Image& b);

// A PSNR for a table column: six characters, "   inf" for identical images.
std::string psnr_text(double db);

// Per pixel, t = the largest channel |a - b| of the tone-mapped values (0..1), shown blue (t = 0, equal)
// -> green (t = 0.5) -> red (t = 1, completely different). Throws std::invalid_argument when sizes differ.
Image difference_image(const Image& a, const Image& b);

} // namespace rcx
