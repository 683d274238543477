// Filtered (bilinear) lookups: the footprint of shared/cube_filter.h and raycache::filtered_value, against
// taps and weights worked out by hand from the Vulkan specification's LINEAR cube filtering, against brute
// force over the cube's texels (the tap past an edge is the neighbouring face's texel nearest the
// direction), and against a smooth analytic environment (continuity across every edge and corner, and
// accuracy within derived bounds). Expected values come from the cube-map table written out again below
// in double precision, never from the library's own answers.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <raycache/filtered_lookup.hpp>

#include "test_random.hpp"

using raycache::FilterFootprint;
using raycache::FilterTap;
using raycache::TexelAddress;
using raycache::filter_footprint;
using raycache::filtered_value;

namespace {

// The cube-map table (OpenGL/Vulkan), written out for the tests: on face f, direction = m * major +
// sc * s_axis + tc * t_axis, and sc, tc in [-1, 1] across the face.
struct Frame {
    glm::dvec3 major, s_axis, t_axis;
};
const Frame frames[6] = {
    {{1, 0, 0}, {0, 0, -1}, {0, -1, 0}},  // +X: sc = -z, tc = -y
    {{-1, 0, 0}, {0, 0, 1}, {0, -1, 0}},  // -X: sc = +z, tc = -y
    {{0, 1, 0}, {1, 0, 0}, {0, 0, 1}},    // +Y: sc = +x, tc = +z
    {{0, -1, 0}, {1, 0, 0}, {0, 0, -1}},  // -Y: sc = +x, tc = -z
    {{0, 0, 1}, {1, 0, 0}, {0, -1, 0}},   // +Z: sc = +x, tc = -y
    {{0, 0, -1}, {-1, 0, 0}, {0, -1, 0}}, // -Z: sc = -x, tc = -y
};

// The face across each edge of each face, read off the table by hand: edges sc = -1, sc = +1, tc = -1,
// tc = +1. (E.g. +X's sc = -z reaches -1 where z = +|x|, on +Z.)
const int neighbour[6][4] = {
    {4, 5, 2, 3}, // +X
    {5, 4, 2, 3}, // -X
    {1, 0, 5, 4}, // +Y
    {1, 0, 4, 5}, // -Y
    {1, 0, 2, 3}, // +Z
    {0, 1, 2, 3}, // -Z
};

glm::dvec3 on_face(int f, double sc, double tc) {
    return frames[f].major + sc * frames[f].s_axis + tc * frames[f].t_axis;
}

// Face coordinate of the centre of texel k of n.
double centre_coordinate(int k, int n) { return (2.0 * k + 1.0) / n - 1.0; }

// Unit direction through a texel's centre.
glm::dvec3 texel_centre(const TexelAddress& t, int n) {
    return glm::normalize(on_face(t.face, centre_coordinate(t.column, n), centre_coordinate(t.row, n)));
}

// The direction at filter position (u, v) of face f, where u = (sc + 1) / 2 * n - 0.5 is the position in
// texels that the specification's bilinear filter floors (u = i0 + alpha); exact in float when n is a
// power of two and u has few bits.
glm::vec3 at_position(int f, double u, double v, int n) {
    const glm::dvec3 d = on_face(f, 2.0 * (u + 0.5) / n - 1.0, 2.0 * (v + 0.5) / n - 1.0);
    return glm::vec3(static_cast<float>(d.x), static_cast<float>(d.y), static_cast<float>(d.z));
}

// The face a vector points into, by its largest magnitude (callers avoid ties).
int major_face(const glm::dvec3& d) {
    const glm::dvec3 a = glm::abs(d);
    if (a.x > a.y && a.x > a.z) return d.x > 0 ? 0 : 1;
    if (a.y > a.z) return d.y > 0 ? 2 : 3;
    return d.z > 0 ? 4 : 5;
}

// The k texels of face g whose centres make the smallest angles with s, nearest first (brute force).
std::vector<TexelAddress> nearest_texels(int g, const glm::dvec3& s, int n, int k) {
    const glm::dvec3 unit = glm::normalize(s);
    std::vector<std::pair<double, TexelAddress>> all;
    all.reserve(static_cast<std::size_t>(n) * n);
    for (int row = 0; row < n; ++row)
        for (int column = 0; column < n; ++column) {
            const TexelAddress t{g, column, row};
            all.push_back({-glm::dot(texel_centre(t, n), unit), t}); // smaller = nearer
        }
    std::partial_sort(all.begin(), all.begin() + k, all.end(),
                      [](const auto& a, const auto& b) { return a.first < b.first; });
    std::vector<TexelAddress> out;
    for (int i = 0; i < k; ++i) out.push_back(all[static_cast<std::size_t>(i)].second);
    return out;
}

// The tap of a footprint reading texel t, or nullptr.
const FilterTap* tap_at(const FilterFootprint& f, const TexelAddress& t) {
    for (const FilterTap& tap : f)
        if (tap.texel == t) return &tap;
    return nullptr;
}

struct Expected {
    TexelAddress texel;
    double weight;
};

// The footprint holds exactly these taps (in any order), weights within `tolerance`.
void check_taps(const glm::vec3& s, int n, const std::vector<Expected>& expected, double tolerance = 0.0) {
    CAPTURE(s.x);
    CAPTURE(s.y);
    CAPTURE(s.z);
    CAPTURE(n);
    const FilterFootprint f = filter_footprint(s, n);
    REQUIRE(f.count == static_cast<int>(expected.size()));
    for (const Expected& e : expected) {
        CAPTURE(e.texel.face);
        CAPTURE(e.texel.column);
        CAPTURE(e.texel.row);
        const FilterTap* tap = tap_at(f, e.texel);
        REQUIRE(tap != nullptr);
        CHECK(std::abs(tap->weight - e.weight) <= tolerance);
    }
}

// The smooth analytic environment: colour = 0.5 + 0.5 * unit direction.
glm::dvec3 environment(const glm::dvec3& d) { return 0.5 + 0.5 * glm::normalize(d); }

// A cube filled with the environment at texel centres (what a perfect cache would hold).
std::optional<glm::vec3> environment_texel(const TexelAddress& t, int n) {
    return glm::vec3(environment(texel_centre(t, n)));
}

glm::dvec3 filtered_environment(const glm::vec3& s, int n) {
    const std::optional<glm::vec3> c = filtered_value(s, n, [n](const TexelAddress& t) { return environment_texel(t, n); });
    REQUIRE(c.has_value());
    return glm::dvec3(*c);
}

double max_abs(const glm::dvec3& v) { return std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)}); }

// One IEEE float rounding of an exact double result (the volatile keeps the compiler from fusing it).
float rounded(double exact) {
    volatile float f = static_cast<float>(exact);
    return f;
}

// The specification's footprint weights with every float operation rounded on its own, as the GPU does
// them under `precise`: u = ((sc * (0.5/m)) + 0.5) * N - 0.5, alpha = u - floor(u), the four products,
// then a missing corner's weight times 1/3 (rounded to float) added to the other three. Returns the
// weights of the taps kept, in footprint order. (Products and sums of floats are exact in double, so
// each `rounded` is one float operation.)
std::vector<float> model_weights(const glm::vec3& s, int n) {
    const glm::dvec3 d(s);
    const int f = major_face(d);
    const float m = rounded(std::abs(glm::dot(d, frames[f].major)));
    const float scale = rounded(0.5 / m);
    auto position = [&](double sc) {
        const float t = rounded(static_cast<double>(rounded(sc * scale)) + 0.5);
        return rounded(static_cast<double>(rounded(static_cast<double>(t) * n)) - 0.5);
    };
    const float u = position(glm::dot(d, frames[f].s_axis)), v = position(glm::dot(d, frames[f].t_axis));
    const float alpha = rounded(u - std::floor(u)), beta = rounded(v - std::floor(v));
    const float alpha0 = rounded(1.0 - alpha), beta0 = rounded(1.0 - beta);
    const float w[4] = {rounded(double(alpha0) * beta0), rounded(double(alpha) * beta0), rounded(double(alpha0) * beta),
                        rounded(double(alpha) * beta)};
    int corner = -1;
    for (int k = 0; k < 4; ++k) {
        const int i = static_cast<int>(std::floor(u)) + k % 2, j = static_cast<int>(std::floor(v)) + k / 2;
        if ((i < 0 || i >= n) && (j < 0 || j >= n)) corner = k;
    }
    const float share = corner < 0 ? 0.0f : rounded(double(w[corner]) * rounded(1.0 / 3.0));
    std::vector<float> kept;
    for (int k = 0; k < 4; ++k) {
        const float weight = rounded(double(w[k]) + share);
        if (k != corner && weight > 0.0f) kept.push_back(weight);
    }
    return kept;
}

} // namespace

TEST_CASE("at a face's centre the four texels around it weigh 1/4 each (even N), or its centre texel 1 (odd N)") {
    for (int f = 0; f < 6; ++f) {
        CAPTURE(f);
        const glm::vec3 s = glm::vec3(frames[f].major) * 3.0f; // any length
        // N = 4: u = 0.5 * 4 - 0.5 = 1.5 -> i0 = 1, alpha = 0.5; likewise v.
        check_taps(s, 4, {{{f, 1, 1}, 0.25}, {{f, 2, 1}, 0.25}, {{f, 1, 2}, 0.25}, {{f, 2, 2}, 0.25}});
        // N = 3: u = 1.5 - 0.5 = 1 -> alpha = 0, one texel. N = 1: u = 0 -> texel (0, 0).
        check_taps(s, 3, {{{f, 1, 1}, 1.0}});
        check_taps(s, 1, {{{f, 0, 0}, 1.0}});
    }
}

TEST_CASE("at a texel's centre that texel alone weighs 1, for every texel") {
    for (int n : {1, 2, 4, 16, 64}) { // centres exact in float: exactly one tap, weight exactly 1
        CAPTURE(n);
        long wrong = 0;
        for (int f = 0; f < 6; ++f)
            for (int row = 0; row < n; ++row)
                for (int column = 0; column < n; ++column) {
                    const FilterFootprint fp = filter_footprint(at_position(f, column, row, n), n);
                    const TexelAddress t{f, column, row};
                    if (fp.count != 1 || fp.taps[0].texel != t || fp.taps[0].weight != 1.0f) ++wrong;
                }
        CHECK(wrong == 0);
    }
    for (int n : {3, 5, 255}) { // centres rounded: the texel weighs 1 up to the rounding of t * N, a few
        CAPTURE(n);            // units of 2^-24 N (1.5e-5 at N = 255)
        long wrong = 0;
        for (int f = 0; f < 6; ++f)
            for (int row = 0; row < n; row += (n > 16 ? 7 : 1))
                for (int column = 0; column < n; column += (n > 16 ? 5 : 1)) {
                    const FilterFootprint fp = filter_footprint(at_position(f, column, row, n), n);
                    const FilterTap* tap = tap_at(fp, {f, column, row});
                    if (!tap || tap->weight < 1.0 - 4 * n * 0x1p-24) ++wrong;
                }
        CHECK(wrong == 0);
    }
}

TEST_CASE("between texels the weights are the bilinear ones, worked by hand") {
    // +X, N = 8: sc = -0.25 -> t = 0.375, u = 3 - 0.5 = 2.5: i0 = 2, alpha = 0.5; tc = 0.375 ->
    // t = 0.6875, v = 5.5 - 0.5 = 5: j0 = 5, beta = 0. Direction (1, -tc, -sc).
    check_taps({1.0f, -0.375f, 0.25f}, 8, {{{0, 2, 5}, 0.5}, {{0, 3, 5}, 0.5}});
    // tc = 0.5 -> t = 0.75, v = 5.5: beta = 0.5 too: four taps of 1/4.
    check_taps({1.0f, -0.5f, 0.25f}, 8, {{{0, 2, 5}, 0.25}, {{0, 3, 5}, 0.25}, {{0, 2, 6}, 0.25}, {{0, 3, 6}, 0.25}});
    // +Y, N = 16, (sc, 1, tc): sc = -0.15625 -> t = 0.421875, u = 6.75 - 0.5 = 6.25: alpha = 0.25;
    // tc = 0.28125 -> t = 0.640625, v = 10.25 - 0.5 = 9.75: beta = 0.75.
    // (1-a)(1-b) = 0.1875, a(1-b) = 0.0625, (1-a)b = 0.5625, ab = 0.1875. Twice as long: the same.
    const std::vector<Expected> expected = {
        {{2, 6, 9}, 0.1875}, {{2, 7, 9}, 0.0625}, {{2, 6, 10}, 0.5625}, {{2, 7, 10}, 0.1875}};
    check_taps({-0.15625f, 1.0f, 0.28125f}, 16, expected);
    check_taps({-0.3125f, 2.0f, 0.5625f}, 16, expected);
}

TEST_CASE("a tap past any of the 24 face edges is the neighbouring face's texel nearest the direction") {
    // On each side of each of the 12 edges: the direction a quarter texel in from the edge (u = -0.25 or
    // N - 0.75, the edges being at -0.5 and N - 0.5), so the tap past the edge weighs 1/4 and the one
    // inside 3/4; along the edge
    // at a texel centre (one tap across) and between two (two taps across, 1/4 * (1 - beta), 1/4 * beta).
    for (int n : {1, 2, 3, 8, 64}) {
        CAPTURE(n);
        const double tolerance = (n & (n - 1)) == 0 ? 0.0 : 1e-6; // non-powers of two round the position
        for (int f = 0; f < 6; ++f)
            for (int edge = 0; edge < 4; ++edge) {
                CAPTURE(f);
                CAPTURE(edge);
                const bool along_s = edge < 2;      // the edge is crossed by moving along sc
                const bool high = edge % 2 == 1;    // at sc or tc = +1
                const double across = high ? n - 0.75 : -0.25;
                const int inside = high ? n - 1 : 0;
                const int g = neighbour[f][edge];
                for (int k : {0, n / 2, n - 1}) {
                    CAPTURE(k);
                    // At a texel centre along the edge: one tap inside, one across.
                    const glm::vec3 s = along_s ? at_position(f, across, k, n) : at_position(f, k, across, n);
                    REQUIRE(major_face(glm::dvec3(s)) == f);
                    const TexelAddress in = along_s ? TexelAddress{f, inside, k} : TexelAddress{f, k, inside};
                    const std::vector<TexelAddress> nearest = nearest_texels(g, glm::dvec3(s), n, 1);
                    check_taps(s, n, {{in, 0.75}, {nearest[0], 0.25}}, tolerance);
                    // Half-way between texel centres k and k + 1 along the edge, beta = 0.3 (both inside).
                    if (k + 1 >= n) continue;
                    const double beta = 0.3;
                    const glm::vec3 s2 = along_s ? at_position(f, across, k + beta, n) : at_position(f, k + beta, across, n);
                    const TexelAddress in0 = along_s ? TexelAddress{f, inside, k} : TexelAddress{f, k, inside};
                    const TexelAddress in1 = along_s ? TexelAddress{f, inside, k + 1} : TexelAddress{f, k + 1, inside};
                    const std::vector<TexelAddress> near2 = nearest_texels(g, glm::dvec3(s2), n, 2);
                    // The nearer of the two across the edge is the one on the nearer row: weight 0.25 * 0.7.
                    check_taps(s2, n,
                               {{in0, 0.75 * 0.7}, {in1, 0.75 * 0.3}, {near2[0], 0.25 * 0.7}, {near2[1], 0.25 * 0.3}},
                               1e-6);
                }
            }
    }
}

TEST_CASE("at and near the 8 cube corners three texels share the missing fourth tap's weight") {
    for (int n : {1, 2, 3, 16}) {
        CAPTURE(n);
        for (int corner = 0; corner < 8; ++corner) {
            CAPTURE(corner);
            const glm::dvec3 c(corner & 1 ? -1 : 1, corner & 2 ? -1 : 1, corner & 4 ? -1 : 1);
            // Exactly at the corner (a tie of all three magnitudes: the Z face's footprint). Each of the
            // three faces meeting there gives its texel at that corner; the fourth (past both of Z's
            // edges) is missing, so 1/4 + (1/4) / 3 = 1/3 each.
            std::vector<Expected> expected;
            for (int axis = 0; axis < 3; ++axis) {
                const int g = 2 * axis + (c[axis] < 0 ? 1 : 0);
                const double sc = glm::dot(c, frames[g].s_axis), tc = glm::dot(c, frames[g].t_axis);
                expected.push_back({{g, sc > 0 ? n - 1 : 0, tc > 0 ? n - 1 : 0}, 1.0 / 3.0});
            }
            check_taps(glm::vec3(c) * 0.5f, n, expected, 1e-7);
            // The same three texels are each the nearest of their face to the corner.
            for (const Expected& e : expected) CHECK(nearest_texels(e.texel.face, c, n, 1)[0] == e.texel);
        }
        // In the corner quarter-texel of every face: u, v = -0.25 or n - 0.75. The tap past both edges
        // weighs 1/4 * 1/4 = 1/16; a third of it goes to each other: inside 9/16 + 1/48 = 28/48, across
        // each edge 3/16 + 1/48 = 10/48, on the neighbour's texel nearest the direction.
        for (int f = 0; f < 6; ++f)
            for (int hs = 0; hs < 2; ++hs)
                for (int ht = 0; ht < 2; ++ht) {
                    CAPTURE(f);
                    const glm::vec3 s = at_position(f, hs ? n - 0.75 : -0.25, ht ? n - 0.75 : -0.25, n);
                    const int gs = neighbour[f][hs], gt = neighbour[f][2 + ht];
                    check_taps(s, n,
                               {{{f, hs ? n - 1 : 0, ht ? n - 1 : 0}, 28.0 / 48},
                                {nearest_texels(gs, glm::dvec3(s), n, 1)[0], 10.0 / 48},
                                {nearest_texels(gt, glm::dvec3(s), n, 1)[0], 10.0 / 48}},
                               (n & (n - 1)) == 0 ? 1e-7 : 1e-6);
                }
    }
}

TEST_CASE("footprints of random directions: 1 to 4 distinct taps on the cube, weights summing to 1, the nearest texel among them") {
    Lcg rng{77};
    for (int n : {1, 2, 3, 16, 255, 4096}) {
        CAPTURE(n);
        long wrong = 0;
        double worst_sum = 0.0;
        for (int i = 0; i < 20000; ++i) {
            glm::vec3 s(rng.signed_uniform(), rng.signed_uniform(), rng.signed_uniform());
            if (i % 3 == 0) s[i / 3 % 3] = std::copysign(std::max({std::abs(s.x), std::abs(s.y), std::abs(s.z)}), s[i / 3 % 3]); // ties
            if (!raycache::is_direction(s)) continue;
            const FilterFootprint f = filter_footprint(s, n);
            double sum = 0.0;
            bool ok = f.count >= 1 && f.count <= 4;
            for (int a = 0; a < f.count; ++a) {
                const FilterTap& t = f.taps[static_cast<std::size_t>(a)];
                ok = ok && raycache::is_on_cube(t.texel, n) && t.weight > 0.0f;
                for (int b = 0; b < a; ++b) ok = ok && f.taps[static_cast<std::size_t>(b)].texel != t.texel;
                sum += t.weight;
            }
            const FilterTap* nearest = tap_at(f, *raycache::texel_of(s, n));
            ok = ok && nearest != nullptr;
            worst_sum = std::max(worst_sum, std::abs(sum - 1.0));
            wrong += !ok;
        }
        CHECK(wrong == 0);
        CHECK(worst_sum <= 4 * 0x1p-24);
    }
}

TEST_CASE("weights and filtered sums are the specification's formulas rounded step by step, bit for bit (no FMA)") {
    // Run also in the build with -mfma -ffp-contract=fast: a fused multiply-add anywhere in the weights,
    // the corner share or the weighted sum changes last bits that this model pins down.
    Lcg rng{4242};
    for (int n : {1, 3, 16, 255, 4096}) {
        CAPTURE(n);
        long wrong_weights = 0, wrong_sums = 0, checked = 0;
        for (int i = 0; i < 20000; ++i) {
            glm::vec3 s(rng.signed_uniform(), rng.signed_uniform(), rng.signed_uniform());
            if (i % 4 == 1) { // in a corner region: the two minor magnitudes within a texel of the major one
                const float m = 0.5f + rng.uniform();
                s = glm::vec3(m, m * (1.0f - rng.uniform() / n), m * (1.0f - rng.uniform() / n));
                if (i % 8 == 1) s = -glm::vec3(s.z, s.x, s.y);
            }
            if (!raycache::is_direction(s) || glm::dot(s, s) < 1e-6f) continue;
            const glm::dvec3 a = glm::abs(glm::dvec3(s));
            if (a.x == a.y || a.y == a.z || a.x == a.z) continue; // the model has no tie rule
            ++checked;
            const FilterFootprint f = filter_footprint(s, n);
            const std::vector<float> want = model_weights(s, n);
            bool same = f.count == static_cast<int>(want.size());
            for (int k = 0; same && k < f.count; ++k)
                same = glm::floatBitsToUint(f.taps[static_cast<std::size_t>(k)].weight) ==
                       glm::floatBitsToUint(want[static_cast<std::size_t>(k)]);
            wrong_weights += !same;
            // The weighted mean of arbitrary colours: products, then sums, then one division per channel.
            const glm::vec3 colors[4] = {{0.1f, 0.7f, 0.3f}, {0.9f, 0.2f, 0.55f}, {0.33f, 0.01f, 0.8f}, {0.6f, 0.6f, 0.1f}};
            int next = 0;
            const std::optional<glm::vec3> got = filtered_value(s, n, [&](const TexelAddress&) {
                return std::optional<glm::vec3>(colors[next++]);
            });
            glm::vec3 sum(0.0f);
            float total = 0.0f;
            for (int k = 0; k < f.count; ++k) {
                const float w = f.taps[static_cast<std::size_t>(k)].weight;
                for (int c = 0; c < 3; ++c) sum[c] = rounded(double(sum[c]) + rounded(double(colors[k][c]) * w));
                total = rounded(double(total) + w);
            }
            const glm::vec3 mean(rounded(sum.x / double(total)), rounded(sum.y / double(total)), rounded(sum.z / double(total)));
            wrong_sums += !(got && glm::floatBitsToUint(*got) == glm::floatBitsToUint(mean));
        }
        CHECK(checked > 10000);
        CHECK(wrong_weights == 0);
        CHECK(wrong_sums == 0);
    }
}

TEST_CASE("vectors that are not directions have no taps, and their filtered lookup reads nothing") {
    const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
    for (const glm::vec3 d : {glm::vec3(0.0f), glm::vec3(-0.0f), glm::vec3(nan, 1, 0), glm::vec3(1, 1, nan),
                              glm::vec3(inf, 0, 0), glm::vec3(0, -inf, 0), glm::vec3(1e-40f, 0, 0), glm::vec3(0, 0, 5e37f)}) {
        CAPTURE(d.x);
        CAPTURE(d.y);
        CAPTURE(d.z);
        CHECK(filter_footprint(d, 16).count == 0);
        int calls = 0;
        CHECK_FALSE(filtered_value(d, 16, [&](const TexelAddress&) {
                        ++calls;
                        return std::optional<glm::vec3>(glm::vec3(1.0f));
                    }).has_value());
        CHECK(calls == 0);
    }
    // Face sizes outside 1..4096 give no taps in the shared function (the C++ wrapper asserts instead).
    CHECK(raycache::shared::raycache_filter_taps_of(glm::vec3(1, 0, 0), 0).count == 0);
    CHECK(raycache::shared::raycache_filter_taps_of(glm::vec3(1, 0, 0), 4097).count == 0);
}

TEST_CASE("empty taps are left out and the others' weights renormalised, worked by hand") {
    // The +Y footprint above: (6,9) 3/16, (7,9) 1/16, (6,10) 9/16, (7,10) 3/16, coloured red, green,
    // blue and white.
    const glm::vec3 s(-0.15625f, 1.0f, 0.28125f);
    const TexelAddress red{2, 6, 9}, green{2, 7, 9}, blue{2, 6, 10}, white{2, 7, 10};
    auto fetch_without = [&](std::vector<TexelAddress> empty, int* calls = nullptr) {
        return [=](const TexelAddress& t) -> std::optional<glm::vec3> {
            if (calls) ++*calls;
            if (std::find(empty.begin(), empty.end(), t) != empty.end()) return std::nullopt;
            if (t == red) return glm::vec3(1, 0, 0);
            if (t == green) return glm::vec3(0, 1, 0);
            if (t == blue) return glm::vec3(0, 0, 1);
            if (t == white) return glm::vec3(1, 1, 1);
            FAIL("a texel outside the footprint was read");
            return std::nullopt;
        };
    };
    auto check_value = [&](std::optional<glm::vec3> got, glm::dvec3 want) {
        REQUIRE(got.has_value());
        CHECK(max_abs(glm::dvec3(*got) - want) <= 1e-6);
    };
    int calls = 0;
    // All four: (3/16 + 3/16, 1/16 + 3/16, 9/16 + 3/16), each tap read once.
    check_value(filtered_value(s, 16, fetch_without({}, &calls)), {0.375, 0.25, 0.75});
    CHECK(calls == 4);
    // One empty: the sum of the rest over their weight.
    check_value(filtered_value(s, 16, fetch_without({red})), glm::dvec3(3, 4, 12) / 13.0);   // /(13/16)
    check_value(filtered_value(s, 16, fetch_without({green})), glm::dvec3(6, 3, 12) / 15.0); // /(15/16)
    check_value(filtered_value(s, 16, fetch_without({blue})), glm::dvec3(6, 4, 3) / 7.0);    // /(7/16)
    check_value(filtered_value(s, 16, fetch_without({white})), glm::dvec3(3, 1, 9) / 13.0);  // /(13/16)
    // Only the lightest left: its colour, whatever its weight. None left: a miss.
    check_value(filtered_value(s, 16, fetch_without({red, blue, white})), {0, 1, 0});
    CHECK_FALSE(filtered_value(s, 16, fetch_without({red, green, blue, white})).has_value());
    // A minimum weight: blue missing leaves 7/16 = 0.4375.
    CHECK_FALSE(filtered_value(s, 16, fetch_without({blue}), 0.5f).has_value());
    check_value(filtered_value(s, 16, fetch_without({blue}), 0.4375f), glm::dvec3(6, 4, 3) / 7.0);
    check_value(filtered_value(s, 16, fetch_without({}), 1.0f - 1e-6f), {0.375, 0.25, 0.75});
}

TEST_CASE("the filtered environment is continuous across all 12 edges and 8 corners") {
    // Pairs of directions on either side of an edge, each delta = 1e-5 from it in its face's coordinates,
    // and the corner with the points delta in from it on each of its three faces. The filtered value is
    // continuous and piecewise bilinear in (u, v); its slope is at most sum |dw/du| * (largest difference
    // between two taps) per texel moved: 2 * (4/3) (the corner rule adds a third) * 0.5 * 1.5 h (taps lie
    // within 1.5 texel widths h = 2/N of each other, colour = 0.5 + 0.5 d), and a face coordinate step of
    // delta moves N/2 * delta texels: 2 * (4/3) * 0.75 * (2/N) * (N/2) = 2 per unit of face coordinate.
    // The longest path between two points of a pair is 2 sqrt(2) delta (corner to point, point to corner),
    // so |change| <= 4 sqrt(2) delta < 6 delta, plus float rounding (2e-6). A seam (a wrong or clamped
    // tap) jumps by about the difference of two neighbouring texels, 0.5 h / 2 = 1/(2N) >= 2e-3 here.
    const double delta = 1e-5;
    const double bound = 6 * delta + 2e-6;
    for (int n : {1, 2, 3, 16, 256}) {
        CAPTURE(n);
        double worst = 0.0;
        int pairs = 0;
        // Edges: the two axes whose magnitudes tie (p, q) with signs, the third coordinate along the edge.
        for (int p = 0; p < 3; ++p)
            for (int q = p + 1; q < 3; ++q)
                for (int signs = 0; signs < 4; ++signs)
                    for (int i = 0; i <= 40; ++i) {
                        const int r = 3 - p - q;
                        const double along = -1.0 + 2.0 * i / 40.0 * (1.0 - 2 * delta) + 2 * delta; // (-1, 1)
                        glm::dvec3 a(0.0), b(0.0);
                        a[p] = b[p] = signs & 1 ? -1.0 : 1.0;
                        a[q] = b[q] = signs & 2 ? -1.0 : 1.0;
                        a[r] = b[r] = along;
                        a[q] *= 1.0 - delta; // into p's face
                        b[p] *= 1.0 - delta; // into q's face
                        REQUIRE(major_face(a) != major_face(b));
                        const double change =
                            max_abs(filtered_environment(glm::vec3(a), n) - filtered_environment(glm::vec3(b), n));
                        worst = std::max(worst, change);
                        ++pairs;
                    }
        // Corners: the three points just inside each face meeting there, and the corner itself.
        for (int corner = 0; corner < 8; ++corner) {
            const glm::dvec3 c(corner & 1 ? -1 : 1, corner & 2 ? -1 : 1, corner & 4 ? -1 : 1);
            std::vector<glm::dvec3> points = {c};
            for (int axis = 0; axis < 3; ++axis) {
                glm::dvec3 v = c * (1.0 - delta);
                v[axis] = c[axis];
                points.push_back(v);
            }
            for (std::size_t x = 0; x < points.size(); ++x)
                for (std::size_t y = x + 1; y < points.size(); ++y) {
                    const double change = max_abs(filtered_environment(glm::vec3(points[x]), n) -
                                                  filtered_environment(glm::vec3(points[y]), n));
                    worst = std::max(worst, change);
                    ++pairs;
                }
        }
        MESSAGE("N = " << n << ": " << pairs << " pairs across edges and corners, largest change " << worst
                       << " (bound " << bound << ")");
        CHECK(worst <= bound);
    }
}

TEST_CASE("the filtered environment is within the derived error bounds of the analytic one") {
    // With colour = 0.5 + 0.5 d (d unit), affine in d, and weights summing to 1, the error of the filtered
    // value is exactly 0.5 * |sum w_i d_i - d|, d_i the texels' unit directions. Texel centres are evenly
    // spaced (h = 2/N) in the face coordinates (a, b), so:
    //   interior (all four taps on the face): bilinear interpolation of d(a, b) = (M + aU + bV)/|.|, whose
    //     second derivatives have norm <= 1 (at the face's centre), errs by <= h^2/8 * (1 + 1), so the
    //     colour by <= h^2/8 = 1/(2 N^2);
    //   edge (taps across one edge): the specification's tap across an edge is the neighbour's edge texel
    //     at the same index along the edge, which is not where the first face's grid, continued, would put
    //     it: it sits |b| h/2 + h^2/4 away (b the coordinate along the edge). Those taps weigh <= 1/2 in
    //     all, so add 0.5 * 0.5 * (h/2 + h^2/4): <= 1/(4N) + 3/(4N^2) in all. First order in h: the
    //     specification's seam is continuous but not smooth;
    //   corner (within half a texel of a corner in both coordinates): the missing tap (weight <= 1/4) is
    //     replaced by the mean of three texels whose centroid lies within h/sqrt(2) of where it would be,
    //     adding 0.5 * 1/4 * h/sqrt(2) = 0.18/N to the edge bound.
    // Plus float rounding, 2e-6. The direction's class comes from its own face coordinates.
    for (int n : {16, 64, 256}) {
        CAPTURE(n);
        const double h = 2.0 / n;
        const double bounds[3] = {h * h / 8 + 2e-6, 1.0 / (4 * n) + 3.0 / (4.0 * n * n) + 2e-6,
                                  1.0 / (4 * n) + 3.0 / (4.0 * n * n) + 0.5 * 0.25 * h / std::sqrt(2.0) + 2e-6};
        const std::string names[3] = {"interior", "edge", "corner"};
        double worst[3] = {0, 0, 0};
        long counts[3] = {0, 0, 0};
        Lcg rng{static_cast<std::uint64_t>(n)};
        for (int i = 0; i < 100000; ++i) {
            glm::vec3 s(rng.signed_uniform(), rng.signed_uniform(), rng.signed_uniform());
            if (glm::dot(s, s) < 1e-6f) continue;
            const glm::dvec3 d(s);
            const int f = major_face(d);
            const double m = std::abs(glm::dot(d, frames[f].major));
            const double a = std::abs(glm::dot(d, frames[f].s_axis) / m), b = std::abs(glm::dot(d, frames[f].t_axis) / m);
            const int cls = (a > 1 - h / 2) + (b > 1 - h / 2); // 0 interior, 1 edge, 2 corner
            const double error = max_abs(filtered_environment(s, n) - environment(d));
            worst[cls] = std::max(worst[cls], error);
            ++counts[cls];
        }
        for (int c = 0; c < 3; ++c) {
            MESSAGE("N = " << n << ", " << names[c] << ": " << counts[c] << " directions, worst error " << worst[c]
                           << " (bound " << bounds[c] << ")");
            CHECK(worst[c] <= bounds[c]);
        }
        CHECK(counts[0] + counts[1] + counts[2] == 100000);
    }
}
