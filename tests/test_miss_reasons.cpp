// Why lookups miss: CubeStatistics::misses_by counts each miss under the state that caused it, so that a
// cache that pays less than expected can say what to change. Every case builds that state by hand and
// expects the count it must give.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <optional>

#include <raycache/raycache.hpp>

using namespace raycache;

namespace {

// The counts of a snapshot, in MissReason order: empty, fresh, doubtful, origin, search, outside.
struct Misses {
    std::uint64_t empty = 0, fresh = 0, doubtful = 0, origin = 0, search = 0, outside = 0;
};

void check_misses(const CubeStatistics& s, std::uint64_t hits, const Misses& m) {
    CHECK(s.hits == hits);
    CHECK(s.misses_by[static_cast<std::size_t>(MissReason::empty)] == m.empty);
    CHECK(s.misses_by[static_cast<std::size_t>(MissReason::fresh)] == m.fresh);
    CHECK(s.misses_by[static_cast<std::size_t>(MissReason::doubtful)] == m.doubtful);
    CHECK(s.misses_by[static_cast<std::size_t>(MissReason::origin)] == m.origin);
    CHECK(s.misses_by[static_cast<std::size_t>(MissReason::search)] == m.search);
    CHECK(s.misses_by[static_cast<std::size_t>(MissReason::outside)] == m.outside);
    const std::uint64_t sum = m.empty + m.fresh + m.doubtful + m.origin + m.search + m.outside;
    CHECK(s.misses == sum);
    CHECK(s.lookups == hits + sum);
}

// The centre direction of texel (face, column, row) of an n-texel face.
glm::vec3 towards(int face, int column, int row, int n) { return texel_direction(TexelAddress{face, column, row}, n); }

// The CDCT cases: a cube of bounds of half-size 1 at the origin, rays along +X.
const CubeBounds unit_bounds{glm::vec3(0.0f), 1.0f};
const glm::vec3 along_x(1.0f, 0.0f, 0.0f);

// Stores a surface at `distance` from the centre into every texel of `cube` but `skip` (this frame's).
void store_everywhere(CdctCube& cube, float distance, std::optional<TexelAddress> skip = std::nullopt) {
    const int n = cube.face_size();
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < n; ++row)
            for (int column = 0; column < n; ++column) {
                const TexelAddress t{face, column, row};
                if (skip && t.face == skip->face && t.column == skip->column && t.row == skip->row) continue;
                REQUIRE(cube.store_at(t, DepthSample{glm::vec3(0.25f), distance}));
            }
}

} // namespace

TEST_CASE("a CCT lookup's miss is counted as empty, fresh, doubtful or outside by its texel's state") {
    const int n = 4; // one tile a face
    CctCube cube(n);
    const glm::vec3 a = towards(4, 1, 2, n), b = towards(4, 2, 2, n); // two texels of +Z's one tile
    const glm::vec3 red(1, 0, 0), green(0, 1, 0);

    // Frame 0: no tile yet (empty), a store then a lookup of it (fresh), two non-directions (outside).
    CHECK_FALSE(cube.lookup(a).has_value());
    CHECK(cube.store(a, red));
    CHECK_FALSE(cube.lookup(a).has_value());
    CHECK_FALSE(cube.lookup(glm::vec3(0.0f)).has_value());
    CHECK_FALSE(cube.lookup(glm::vec3(std::numeric_limits<float>::quiet_NaN(), 0.0f, 1.0f)).has_value());
    check_misses(cube.begin_frame(), 0, Misses{1, 1, 0, 0, 0, 2});

    // Frame 1: a hit, a texel of the same (now allocated) tile that holds nothing (empty), and a search's
    // own count through record_lookup (search).
    CHECK(cube.lookup(a).has_value());
    CHECK_FALSE(cube.lookup(b).has_value());
    CHECK(cube.store(b, green));
    cube.record_lookup(false);
    check_misses(cube.begin_frame(), 1, Misses{1, 0, 0, 0, 1, 0});

    // Between frames a's texel is marked doubtful: kept, not answered (doubtful); b is answered.
    REQUIRE(cube.set_doubtful(*cube.texel_of(a)));
    CHECK_FALSE(cube.lookup(a).has_value());
    CHECK(cube.lookup(b).has_value());
    cube.record_miss(MissReason::fresh); // a caller's own reason is counted as given
    check_misses(cube.begin_frame(), 1, Misses{0, 1, 1, 0, 0, 0});

    // why_missed names the same states without counting.
    CHECK(cube.why_missed(a) == MissReason::doubtful);
    CHECK(cube.why_missed_at(*cube.texel_of(a)) == MissReason::doubtful);
    CHECK(cube.why_missed_at(TexelAddress{6, 0, 0}) == MissReason::outside); // no such face
    CHECK(cube.why_missed(towards(0, 0, 0, n)) == MissReason::empty);
    CHECK(cube.why_missed(glm::vec3(0.0f)) == MissReason::outside);
    CHECK(cube.statistics().lookups == 0u);
}

TEST_CASE("a CCT lookup from further than the drift from its tile's origins is counted as origin, and the dropped tile as empty") {
    CctCube cube(4);
    const glm::vec3 d = towards(0, 1, 1, 4);
    const OriginTolerance tolerance{0.1f};
    CHECK(cube.store(d, glm::vec3(0.5f), glm::vec3(0.0f), std::numeric_limits<float>::infinity(), tolerance));
    cube.begin_frame();
    // 1.0 from the box (a single point at the origin) on x: beyond 0.1. 0.05 away: within it, and the tile,
    // though marked stale by the first lookup, still answers until the next begin_frame().
    CHECK_FALSE(cube.lookup(d, glm::vec3(1.0f, 0.0f, 0.0f), tolerance).has_value());
    CHECK(cube.lookup(d, glm::vec3(0.05f, 0.0f, 0.0f), tolerance).has_value());
    check_misses(cube.begin_frame(), 1, Misses{0, 0, 0, 1, 0, 0});
    CHECK_FALSE(cube.lookup(d, glm::vec3(0.0f), tolerance).has_value());
    check_misses(cube.statistics(), 0, Misses{1, 0, 0, 0, 0, 0});
}

TEST_CASE("a CDCT secant search's miss is counted by the texel whose read ended it, or as search") {
    // Bounds of half-size 1 at the origin; a ray from the centre along +X reads first at the box exit
    // (1, 0, 0), the texel of +X's centre. Every texel at distance 5: f = 1 - 5 < 0 there, so the search
    // needs a second read (at distance 5, on the surface) to hit.
    const CubeBounds& bounds = unit_bounds;
    const glm::vec3 origin(0.0f);
    ReliefParameters p;
    p.search = DepthSearch::secant;
    CdctCube cube(8);

    CHECK_FALSE(secant_search(cube, bounds, origin, along_x, p).hit); // no tile yet
    store_everywhere(cube, 5.0f);
    CHECK_FALSE(secant_search(cube, bounds, origin, along_x, p).hit); // stored this frame
    CHECK_FALSE(secant_search(cube, bounds, origin, glm::vec3(0.0f), p).hit); // not a direction: no read
    check_misses(cube.begin_frame(), 0, Misses{1, 1, 0, 0, 0, 1});

    const ReliefResult found = secant_search(cube, bounds, origin, along_x, p);
    CHECK(found.hit);
    CHECK(found.texels_read == 2);
    p.max_reads = 1; // the first read is not on the surface: out of reads
    CHECK_FALSE(secant_search(cube, bounds, origin, along_x, p).hit);
    check_misses(cube.begin_frame(), 1, Misses{0, 0, 0, 0, 1, 0});

    REQUIRE(cube.set_doubtful(*cube.texel_of(along_x))); // the first read's texel
    p.max_reads = 8;
    CHECK_FALSE(secant_search(cube, bounds, origin, along_x, p).hit);
    check_misses(cube.begin_frame(), 0, Misses{0, 0, 1, 0, 0, 0});
}

TEST_CASE("a CDCT secant search whose second read finds nothing is counted by that texel") {
    // From (0, 0.5, 0) along +X (bounds of half-size 1 at the origin, every texel at distance 5): the first
    // read is at the box exit (1, 0.5, 0), the second where the ray reaches distance 5, (sqrt(24.75), 0.5,
    // 0). On 8-texel faces those lie in rows 2 and 3 of +X. Leaving the second's texel empty makes the
    // search read it and miss there.
    const glm::vec3 origin(0.0f, 0.5f, 0.0f);
    CdctCube cube(8);
    const TexelAddress first = *cube.texel_of(glm::vec3(1.0f, 0.5f, 0.0f));
    const TexelAddress second = *cube.texel_of(glm::vec3(std::sqrt(24.75f), 0.5f, 0.0f));
    REQUIRE(first.row != second.row);
    store_everywhere(cube, 5.0f, second);
    cube.begin_frame();
    ReliefParameters p;
    p.search = DepthSearch::secant;
    const ReliefResult r = secant_search(cube, unit_bounds, origin, along_x, p);
    CHECK_FALSE(r.hit);
    CHECK(r.texels_read == 2);
    check_misses(cube.begin_frame(), 0, Misses{1, 0, 0, 0, 0, 0});
}

TEST_CASE("a CDCT relief walk's miss is counted by the texel whose read ended it, outside for bad input") {
    // The thesis's walk (no pyramid) from the centre along +X reads first at the box exit, +X's centre.
    const CubeBounds& bounds = unit_bounds;
    const glm::vec3 origin(0.0f);
    ReliefParameters p;
    p.search = DepthSearch::relief;
    CdctCube cube(8);
    CHECK_FALSE(relief_search(cube, bounds, origin, along_x, p).hit);          // no tile yet: empty
    CHECK_FALSE(relief_search(cube, bounds, origin, glm::vec3(0.0f), p).hit);  // not a direction: outside
    store_everywhere(cube, 5.0f);
    CHECK_FALSE(relief_search(cube, bounds, origin, along_x, p).hit);          // stored this frame: fresh
    check_misses(cube.begin_frame(), 0, Misses{1, 1, 0, 0, 0, 1});

    CHECK(relief_search(cube, bounds, origin, along_x, p).hit);
    REQUIRE(cube.set_doubtful(*cube.texel_of(along_x)));
    check_misses(cube.begin_frame(), 1, Misses{0, 0, 0, 0, 0, 0});
    CHECK_FALSE(relief_search(cube, bounds, origin, along_x, p).hit);          // the box exit's texel: doubtful
    check_misses(cube.begin_frame(), 0, Misses{0, 0, 1, 0, 0, 0});
}

TEST_CASE("a lookup of a texel off the cube counts as outside") {
    CctCube cube(4);
    CHECK(cube.why_missed_at(TexelAddress{0, 4, 0}) == MissReason::outside); // column 4 of a 4-texel face
    CHECK(cube.why_missed_at(TexelAddress{0, 3, 0}) == MissReason::empty);
}

TEST_CASE("filtered_cached_trace counts its miss by the direction's own texel") {
    CctCube cube(4);
    const glm::vec3 d = towards(2, 1, 1, 4);
    auto trace = [] { return glm::vec3(0.5f); };
    (void)filtered_cached_trace(cube, d, trace); // no tile yet: empty, then stored
    (void)filtered_cached_trace(cube, d, trace); // stored this frame: fresh
    check_misses(cube.begin_frame(), 0, Misses{1, 1, 0, 0, 0, 0});
    (void)filtered_cached_trace(cube, d, trace);
    check_misses(cube.begin_frame(), 1, Misses{});
}
