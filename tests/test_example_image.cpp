// Images of the examples (rcx/image.hpp): the tone map, PSNR and errors against hand-computed values, the
// blue-to-red difference image, and PNG output read back.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>

#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

#include "rcx/image.hpp"

TEST_CASE("the tone map clamps, applies gamma 2.2 and rounds to 8 bits") {
    CHECK(rcx::tone_map(0.0f) == 0);
    CHECK(rcx::tone_map(-1.0f) == 0);
    CHECK(rcx::tone_map(std::numeric_limits<float>::quiet_NaN()) == 0);
    CHECK(rcx::tone_map(1.0f) == 255);
    CHECK(rcx::tone_map(7.0f) == 255);
    CHECK(rcx::tone_map(0.5f) == 186); // 255 * 0.5^(1/2.2) = 186.08
    CHECK(rcx::tone_map(0.2f) == 123); // 255 * 0.2^(1/2.2) = 122.69
}

TEST_CASE("identical images have infinite PSNR and no error") {
    rcx::Image a(5, 3, glm::vec3(0.25f, 0.5f, 2.0f));
    const rcx::ImageDifference d = rcx::compare(a, a);
    CHECK(std::isinf(d.psnr_db));
    CHECK(d.psnr_db > 0.0);
    CHECK(d.mean_abs_error == 0.0);
    CHECK(d.max_abs_error == 0.0);
    CHECK(d.differing_pixels == 0);
    CHECK(d.pixels == 15);
}

TEST_CASE("PSNR and errors of a known difference equal the hand-computed values") {
    SUBCASE("one of two pixels black against white") {
        rcx::Image a(2, 1), b(2, 1);
        b.at(0, 0) = glm::vec3(1.0f);
        // MSE = 3 * 255^2 / 6 channels = 255^2 / 2, so PSNR = 10 log10(2) dB.
        const rcx::ImageDifference d = rcx::compare(a, b);
        CHECK(d.psnr_db == doctest::Approx(10.0 * std::log10(2.0)));
        CHECK(d.mean_abs_error == doctest::Approx(0.5));
        CHECK(d.max_abs_error == doctest::Approx(1.0));
        CHECK(d.differing_pixels == 1);
    }
    SUBCASE("one channel of one of four pixels off by 0.5 linear (186 of 255)") {
        rcx::Image a(2, 2), b(2, 2);
        b.at(1, 1).g = 0.5f;
        // MSE = 186^2 / 12 channels.
        const rcx::ImageDifference d = rcx::compare(a, b);
        CHECK(d.psnr_db == doctest::Approx(10.0 * std::log10(255.0 * 255.0 * 12.0 / (186.0 * 186.0))));
        CHECK(d.mean_abs_error == doctest::Approx(186.0 / 255.0 / 12.0));
        CHECK(d.max_abs_error == doctest::Approx(186.0 / 255.0));
        CHECK(d.differing_pixels == 1);
    }
    CHECK_THROWS_AS(rcx::compare(rcx::Image(2, 2), rcx::Image(2, 3)), std::invalid_argument);
}

TEST_CASE("the difference image is blue where equal, green half-way and red where completely different") {
    rcx::Image a(3, 1), b(3, 1);
    b.at(1, 0) = glm::vec3(0.0f, 0.2196f, 0.0f); // tone-maps to 128: t = 128/255, just past half-way
    b.at(2, 0) = glm::vec3(1.0f, 1.0f, 1.0f);
    const rcx::Image d = rcx::difference_image(a, b);
    CHECK(d.at(0, 0) == glm::vec3(0.0f, 0.0f, 1.0f));
    CHECK(d.at(1, 0).g > 0.98f);
    CHECK(d.at(1, 0).r < 0.02f);
    CHECK(d.at(1, 0).b == 0.0f);
    CHECK(d.at(2, 0) == glm::vec3(1.0f, 0.0f, 0.0f));
    CHECK_THROWS_AS(rcx::difference_image(rcx::Image(1, 1), rcx::Image(2, 1)), std::invalid_argument);
}

TEST_CASE("write_png writes the tone-mapped pixels and throws with the path when it cannot write") {
    const std::filesystem::path dir = std::filesystem::temp_directory_path();
    const std::string path = (dir / "raycache-test-example-image.png").string();
    rcx::Image image(4, 2);
    image.at(0, 0) = glm::vec3(1.0f, 0.0f, 0.5f);
    image.at(3, 1) = glm::vec3(0.2f, 9.0f, -1.0f);
    rcx::write_png(path, image);
    int w = 0, h = 0, channels = 0;
    unsigned char* rgb = stbi_load(path.c_str(), &w, &h, &channels, 3);
    REQUIRE(rgb != nullptr);
    CHECK(w == 4);
    CHECK(h == 2);
    CHECK(rgb[0] == 255);
    CHECK(rgb[1] == 0);
    CHECK(rgb[2] == 186);
    const int last = 3 * (1 * 4 + 3);
    CHECK(rgb[last + 0] == 123);
    CHECK(rgb[last + 1] == 255);
    CHECK(rgb[last + 2] == 0);
    stbi_image_free(rgb);
    std::filesystem::remove(path);

    const std::string missing = (dir / "raycache-no-such-folder" / "x.png").string();
    CHECK_THROWS_WITH_AS(rcx::write_png(missing, image), doctest::Contains(missing.c_str()), std::runtime_error);
    CHECK_THROWS_WITH_AS(rcx::write_png(missing, image), doctest::Contains("does not exist"), std::runtime_error);
    CHECK_THROWS_WITH_AS(rcx::write_png("/proc/raycache.png", image), doctest::Contains("/proc/raycache.png"),
                         std::runtime_error);
    CHECK_THROWS_AS(rcx::write_png((dir / "empty.png").string(), rcx::Image()), std::runtime_error);
}

TEST_CASE("psnr_text is six characters wide, two decimals, and says inf for identical images") {
    CHECK(rcx::psnr_text(std::numeric_limits<double>::infinity()) == "   inf");
    CHECK(rcx::psnr_text(37.912) == " 37.91");
    CHECK(rcx::psnr_text(5.0) == "  5.00");
    CHECK(rcx::psnr_text(104.5) == "104.50");
}

TEST_CASE("bit_identical compares every float bit: one ulp, a signed zero or a size differs") {
    rcx::Image a(3, 2, glm::vec3(0.25f, 0.5f, 0.75f));
    rcx::Image b = a;
    CHECK(rcx::bit_identical(a, b));
    b.pixels[4].y = std::nextafter(0.5f, 1.0f);
    CHECK_FALSE(rcx::bit_identical(a, b));
    CHECK(rcx::compare(a, b).differing_pixels == 0); // invisible after tone mapping, yet not identical
    b = a;
    a.pixels[0].x = 0.0f;
    b.pixels[0].x = -0.0f;
    CHECK_FALSE(rcx::bit_identical(a, b));
    CHECK_FALSE(rcx::bit_identical(rcx::Image(3, 2), rcx::Image(2, 3)));
}
