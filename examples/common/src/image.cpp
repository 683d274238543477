// Images: tone map, PNG output (stb_image_write), comparison and difference images.
#include "rcx/image.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <stdexcept>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#include <stb/stb_image_write.h>

namespace rcx {

Image::Image(int w, int h, glm::vec3 fill) : width(w), height(h) {
    if (w < 0 || h < 0)
        throw std::invalid_argument("Image: size must be >= 0, got " + std::to_string(w) + "x" + std::to_string(h));
    pixels.assign(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), fill);
}

std::uint8_t tone_map(float linear) {
    if (!(linear > 0.0f)) return 0; // also NaN
    if (linear >= 1.0f) return 255;
    return static_cast<std::uint8_t>(std::lround(255.0 * std::pow(static_cast<double>(linear), 1.0 / 2.2)));
}

namespace {

std::vector<std::uint8_t> to_rgb8(const Image& image) {
    std::vector<std::uint8_t> rgb(image.pixels.size() * 3);
    for (std::size_t i = 0; i < image.pixels.size(); ++i)
        for (int c = 0; c < 3; ++c) rgb[3 * i + static_cast<std::size_t>(c)] = tone_map(image.pixels[i][c]);
    return rgb;
}

struct Output {
    std::FILE* file;
    bool failed;
};

void write_bytes(void* context, void* data, int size) {
    Output* out = static_cast<Output*>(context);
    if (std::fwrite(data, 1, static_cast<std::size_t>(size), out->file) != static_cast<std::size_t>(size)) out->failed = true;
}

void check_same_size(const Image& a, const Image& b, const char* what) {
    if (a.width != b.width || a.height != b.height)
        throw std::invalid_argument(std::string(what) + ": images differ in size (" + std::to_string(a.width) + "x" +
                                    std::to_string(a.height) + " vs " + std::to_string(b.width) + "x" +
                                    std::to_string(b.height) + ")");
}

// |a - b| of every tone-mapped channel, in to_rgb8's order: what compare() and difference_image() measure.
std::vector<int> channel_errors(const Image& a, const Image& b, const char* what) {
    check_same_size(a, b, what);
    const std::vector<std::uint8_t> ra = to_rgb8(a), rb = to_rgb8(b);
    std::vector<int> errors(ra.size());
    for (std::size_t k = 0; k < ra.size(); ++k) errors[k] = std::abs(int(ra[k]) - int(rb[k]));
    return errors;
}

} // namespace

void write_png(const std::string& path, const Image& image) {
    if (image.width <= 0 || image.height <= 0)
        throw std::runtime_error("cannot write '" + path + "': the image is empty");
    // Open the file ourselves, so a failure can say why (stb only says that it failed).
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) {
        const int err = errno;
        std::string reason = std::strerror(err);
        const std::filesystem::path parent = std::filesystem::path(path).parent_path();
        std::error_code ec;
        if (!parent.empty() && !std::filesystem::is_directory(parent, ec)) reason = "folder '" + parent.string() + "' does not exist";
        throw std::runtime_error("cannot write '" + path + "': " + reason);
    }
    const std::vector<std::uint8_t> rgb = to_rgb8(image);
    Output out{f, false};
    const int ok = stbi_write_png_to_func(write_bytes, &out, image.width, image.height, 3, rgb.data(), image.width * 3);
    const bool write_error = out.failed || std::ferror(f) != 0;
    const bool close_error = std::fclose(f) != 0;
    if (!ok || write_error || close_error)
        throw std::runtime_error("cannot write '" + path + "': " +
                                 (!ok ? std::string("PNG encoding failed") : std::string("write error (disk full?)")));
}

bool bit_identical(const Image& a, const Image& b) {
    return a.width == b.width && a.height == b.height && a.pixels.size() == b.pixels.size() &&
           std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(glm::vec3)) == 0;
}

std::string psnr_text(double db) {
    if (std::isinf(db)) return "   inf";
    char text[32];
    std::snprintf(text, sizeof text, "%6.2f", db);
    return text;
}

ImageDifference compare(const Image& a, const Image& b) {
    const std::vector<int> errors = channel_errors(a, b, "compare");
    ImageDifference d;
    d.pixels = a.pixels.size();
    double squared = 0.0, absolute = 0.0;
    int largest = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i) {
        bool differs = false;
        for (std::size_t c = 0; c < 3; ++c) {
            const int e = errors[3 * i + c];
            squared += double(e) * e;
            absolute += e;
            largest = std::max(largest, e);
            differs = differs || e != 0;
        }
        d.differing_pixels += differs ? 1 : 0;
    }
    const double channels = 3.0 * static_cast<double>(std::max<std::size_t>(d.pixels, 1));
    const double mse = squared / channels;
    d.psnr_db = mse == 0.0 ? std::numeric_limits<double>::infinity() : 10.0 * std::log10(255.0 * 255.0 / mse);
    d.mean_abs_error = absolute / channels / 255.0;
    d.max_abs_error = largest / 255.0;
    return d;
}

Image difference_image(const Image& a, const Image& b) {
    const std::vector<int> errors = channel_errors(a, b, "difference_image");
    Image out(a.width, a.height);
    const glm::vec3 blue(0.0f, 0.0f, 1.0f), green(0.0f, 1.0f, 0.0f), red(1.0f, 0.0f, 0.0f);
    for (std::size_t i = 0; i < a.pixels.size(); ++i) {
        const int e = std::max({errors[3 * i], errors[3 * i + 1], errors[3 * i + 2]});
        const float t = static_cast<float>(e) / 255.0f;
        out.pixels[i] = t < 0.5f ? glm::mix(blue, green, 2.0f * t) : glm::mix(green, red, 2.0f * t - 1.0f);
    }
    return out;
}

} // namespace rcx
