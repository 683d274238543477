// Exact invalidation of a CDCT cube (raycache/invalidation.hpp) in the analytic world of analytic_world.hpp:
// the mirror ball's CDCT cube is filled with traced rays (their hit points, keyed by direction from the
// centre, with their path records). A CDCT texel holding point P at distance s answers rays from the box
// that meet the stored surface there, so the oracle retraces, for every texel still valid, rays from random
// points of the box toward points at distance s in random directions of the texel, in the world before and
// after the move; a sample counts when, before the move, the ray met a surface within 2% of that distance
// (the texel's surface, not something in front of it or a miss beside it), or, for a stored escape, met
// nothing. A texel is stale when a counted sample sees another colour after the move. A second oracle asks
// the searches themselves: an answer that was right before a move is right after it, or a miss.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#include <glm/glm.hpp>

#include "raycache/cdct.hpp"
#include "raycache/cdct_cache.hpp"
#include "raycache/cube_face.hpp"
#include "raycache/invalidation.hpp"
#include "raycache/path_record.hpp"

#include "analytic_world.hpp"

namespace {

using namespace analytic;
using raycache::CdctCache;
using raycache::CdctCube;

// The Embree tracer's search: a crossing more than 0.5 behind the stored surface is a miss, so a texel's
// rays end within its distance + 0.5 of the centre.
raycache::ReliefParameters search_parameters() {
    raycache::ReliefParameters p;
    p.max_gap = 0.5f;
    return p;
}
const raycache::ReliefParameters parameters = search_parameters();

// Fills a cube as the mirror ball's rays would: from points of its surface into their normal's half-space,
// traced in `w`, stored with their path records (store_traced, as cdct_cached_trace stores a miss).
void fill(CdctCube& cube, const World& w, int stores, unsigned seed) {
    LeavingRays leaving(seed);
    for (int k = 0; k < stores; ++k) {
        const auto [n, d] = leaving.next();
        PathRecord path;
        const raycache::TracedRay t = w.traced(n, d, &path);
        raycache::store_traced(cube, box, n, d, t, parameters, &path);
    }
    cube.begin_frame();
}

struct Oracle {
    std::size_t stale = 0;   // texels with a counted sample whose colour changed
    std::size_t samples = 0; // counted samples
};

Oracle stale_texels(const CdctCube& cube, const World& before, const World& after) {
    Sampler s;
    Oracle o;
    const int n = cube.face_size();
    cube.for_each_valid_texel([&](const TexelAddress& a) {
        const raycache::DepthSample stored = *cube.load(a);
        const bool escape = stored.distance >= parameters.max_depth;
        for (int k = 0; k < 48; ++k) {
            const glm::vec3 origin = s.origin(k), point = box.centre + stored.distance * s.direction(a, n);
            const float length = glm::length(point - origin);
            const glm::vec3 d = (point - origin) / length;
            float t = 0.0f;
            const bool hit = before.nearest(origin, d, &t) >= 0;
            if (escape ? hit : (!hit || std::abs(t - length) > 0.02f * length)) continue;
            ++o.samples;
            if (glm::any(glm::greaterThan(glm::abs(before.trace(origin, d) - after.trace(origin, d)), glm::vec3(1e-6f)))) {
                ++o.stale;
                return;
            }
        }
    });
    return o;
}


// The record blocks of a cube whose Bloom masks hold the bits of object `key` (such blocks are dropped
// whole by their path records, whatever their texels' cones).
std::vector<CdctCube::BlockState> blocks_maybe_tagged(const CdctCube& cube, std::uint64_t key) {
    std::vector<CdctCube::BlockState> maybe;
    cube.for_each_block_state([&](const CdctCube::BlockState& b) {
        if ((b.objects & raycache::object_bits(key)) == raycache::object_bits(key)) maybe.push_back(b);
    });
    return maybe;
}
bool in_any(const std::vector<CdctCube::BlockState>& blocks, const TexelAddress& a) {
    for (const CdctCube::BlockState& b : blocks)
        if (a.face == b.face && a.column >= b.column0 && a.column < b.column1 && a.row >= b.row0 && a.row < b.row1) return true;
    return false;
}

} // namespace

TEST_CASE("CDCT: after a sphere moves, exact invalidation leaves no stale texel, without it the oracle finds them") {
    const World before = make_world();
    for (const auto& [moved, after] : test_moves(before)) {
        CAPTURE(moved);
        CdctCube kept(32), exact(32);
        fill(kept, before, 30000, 1);
        fill(exact, before, 30000, 1);
        const std::size_t valid = exact.valid_texels();
        REQUIRE(valid > 2000);

        const Oracle without = stale_texels(kept, before, after);
        const raycache::InvalidationCounts counts = raycache::invalidate_changes(exact, box, parameters, move_of(before, after, moved));
        const Oracle with = stale_texels(exact, before, after);
        MESSAGE("ball " << moved << ": " << valid << " texels, " << without.stale << " stale without invalidation ("
                        << without.samples << " samples), " << counts.dropped << " dropped by exact (" << counts.blocks_by_path
                        << " blocks by path, " << counts.blocks_by_texel << " tested per texel), " << with.stale << " stale after ("
                        << with.samples << " samples)");
        CHECK(without.stale > 0);
        CHECK(with.samples > 20 * exact.valid_texels()); // most texels' samples meet their surface
        CHECK(with.stale == 0);
        CHECK(counts.dropped == valid - exact.valid_texels());
        CHECK(counts.dropped < valid / 2); // it keeps most of the cube
    }
}

TEST_CASE("CDCT: a sphere moving where no stored path went drops exactly the texels whose cones can reach it") {
    const World w = make_world();
    CdctCube cube(32);
    fill(cube, w, 30000, 5);
    // Far to the side, below the light's cone over the hit points; never hit by a stored path.
    const std::uint64_t key = 99;
    raycache::SceneChanges changes;
    const raycache::BoundingSphere from{glm::vec3(30.0f, 0.0f, 0.0f), 4.0f}, to{glm::vec3(30.0f, 2.0f, 0.0f), 4.0f};
    changes.moved.push_back({key, from, to});
    changes.lights.push_back(w.light);

    // Blocks whose Bloom masks happen to hold the key's bits are dropped whole: leave them out.
    const std::vector<CdctCube::BlockState> bloom_says_maybe = blocks_maybe_tagged(cube, key);
    // From angles: a texel's rays (origins within the box's ball, radius sqrt(3)) reach a sphere only
    // within its angular radius grown by that ball, plus half the texel's diagonal (< 3 degrees at 32).
    auto angle_to = [](const TexelAddress& a, const raycache::BoundingSphere& s) {
        const glm::vec3 d = glm::normalize(raycache::texel_direction(a, 32));
        const float dist = glm::length(s.centre);
        return std::acos(glm::clamp(glm::dot(d, s.centre / dist), -1.0f, 1.0f)) -
               std::asin(std::min(1.0f, (s.radius + 1.7321f) / dist));
    };
    const float margin = 3.0f * 3.14159265f / 180.0f;
    std::vector<TexelAddress> must_keep, must_drop;
    cube.for_each_valid_texel([&](const TexelAddress& a) {
        if (in_any(bloom_says_maybe, a)) return;
        const float nearest = std::min(angle_to(a, from), angle_to(a, to));
        if (nearest > margin) must_keep.push_back(a);
        // The centre direction itself, from the centre, passes through a sphere: some ray of the texel does,
        // unless it ends at a surface nearer than the sphere (only escapes reach it here).
        else if (nearest < -std::asin(1.7321f / 30.0f) && cube.load(a)->distance >= parameters.max_depth) must_drop.push_back(a);
    });
    const raycache::InvalidationCounts counts = raycache::invalidate_changes(cube, box, parameters, changes);
    std::size_t kept = 0, dropped = 0;
    for (const TexelAddress& a : must_keep) kept += cube.load(a).has_value();
    for (const TexelAddress& a : must_drop) dropped += !cube.load(a).has_value();
    MESSAGE(counts.valid_before << " texels: " << must_keep.size() << " clearly away, " << kept << " kept; " << must_drop.size()
                                << " clearly in a cone, " << dropped << " dropped; " << counts.dropped << " dropped in all");
    CHECK(must_keep.size() > 3000);
    CHECK(kept == must_keep.size());
    CHECK(!must_drop.empty());
    CHECK(dropped == must_drop.size());
    CHECK(counts.blocks_by_path == 0);
}

TEST_CASE("CDCT: a sphere moving behind the surfaces a texel holds keeps the texel, the escapes it blocks go") {
    // Ball 3 seen from the centre; a new sphere moves further out in the same direction, behind it. Texels
    // holding ball 3's surface end their rays within distance + 0.5 of the centre, short of the sphere; the
    // texels whose rays escaped past ball 3 toward the sphere now meet it.
    const World w = make_world();
    CdctCube cube(32), without_reach(32);
    fill(cube, w, 30000, 6);
    fill(without_reach, w, 30000, 6);
    const glm::vec3 toward = glm::normalize(w.balls[3].centre);
    const float far = glm::length(w.balls[3].centre) + 9.0f, radius = 3.0f;
    raycache::SceneChanges changes;
    changes.moved.push_back({77, {far * toward, radius}, {far * toward + glm::vec3(0.0f, 0.5f, 0.0f), radius}});
    changes.lights.push_back(w.light);

    const std::vector<CdctCube::BlockState> bloom_says_maybe = blocks_maybe_tagged(cube, 77);
    std::vector<TexelAddress> short_of_it, escapes_toward_it;
    // Toward it: the texel's centre direction from the centre passes through the sphere (so some ray of
    // the texel meets it).
    const float inside = std::asin(radius / far);
    cube.for_each_valid_texel([&](const TexelAddress& a) {
        if (in_any(bloom_says_maybe, a)) return;
        const glm::vec3 d = glm::normalize(raycache::texel_direction(a, 32));
        const raycache::DepthSample v = *cube.load(a);
        if (std::acos(glm::clamp(glm::dot(d, toward), -1.0f, 1.0f)) > inside) return;
        if (v.distance >= parameters.max_depth) escapes_toward_it.push_back(a);
        else if (v.distance + 0.5f < far - radius - 2.0f) short_of_it.push_back(a);
    });
    raycache::invalidate_changes(cube, box, parameters, changes);
    raycache::invalidate_changes(without_reach, {box, -1.0f}, changes); // every ray taken as unbounded
    std::size_t kept = 0, kept_without_reach = 0, escapes_kept = 0;
    for (const TexelAddress& a : short_of_it) kept += cube.load(a).has_value(), kept_without_reach += without_reach.load(a).has_value();
    for (const TexelAddress& a : escapes_toward_it) escapes_kept += cube.load(a).has_value();
    MESSAGE(short_of_it.size() << " texels toward the sphere hold nearer surfaces: " << kept << " kept (" << kept_without_reach
                               << " when rays are taken as unbounded); " << escapes_toward_it.size() << " escapes toward it, "
                               << escapes_kept << " kept");
    CHECK(short_of_it.size() >= 10); // ball 3 covers a dozen texels at 32 a face
    CHECK(kept == short_of_it.size());
    CHECK(kept_without_reach == 0);
    CHECK(escapes_kept == 0);
}

TEST_CASE("CDCT: cdct_cached_trace stores a recording trace's path, exact invalidation of a CdctCache keeps its searches valid") {
    // Through the cache's own path: misses traced with their records, then a move of one ball; afterwards
    // every search that still answers gives the colour the moved world shows (within the CDCT's own
    // error: compared with the unmoved cache's answers, which must equal them where the move changed nothing).
    const World before = make_world();
    World after = before;
    const std::size_t moved = 4;
    after.balls[moved].centre += glm::vec3(0.0f, 0.6f, 0.0f);
    raycache::ReliefParameters p = parameters;
    p.search = raycache::DepthSearch::relief;
    CdctCache cache(32, box, p);
    LeavingRays leaving(8);
    std::vector<std::pair<glm::vec3, glm::vec3>> rays;
    for (int k = 0; k < 30000; ++k) {
        const std::pair<glm::vec3, glm::vec3> ray = leaving.next();
        const glm::vec3 n = ray.first, d = ray.second; // (a lambda below captures them)
        rays.push_back(ray);
        cache.cached_trace(n, d, [&](PathRecord& path) { return before.traced(n, d, &path); });
        if (k % 5000 == 4999) cache.begin_frame();
    }
    cache.begin_frame();
    // No block may hold an unrecorded texel: every store came with its record.
    std::size_t unrecorded = 0;
    cache.cube().for_each_block_state([&](const CdctCube::BlockState& t) { unrecorded += t.unrecorded_texels; });
    CHECK(unrecorded == 0);

    const std::size_t valid = cache.cube().valid_texels();
    const raycache::InvalidationCounts counts = raycache::invalidate_changes(cache, move_of(before, after, moved));
    CHECK(counts.dropped > 0);
    CHECK(counts.dropped < valid / 2);
    // Rays aimed at the moved ball (before or after) are no longer answered by the cache.
    std::size_t answered_at_ball = 0, aimed = 0;
    for (const auto& [o, d] : rays) {
        const int before_hit = before.nearest(o, d, nullptr), after_hit = after.nearest(o, d, nullptr);
        if (before_hit != static_cast<int>(moved) && after_hit != static_cast<int>(moved)) continue;
        ++aimed;
        answered_at_ball += cache.lookup(o, d).hit;
    }
    MESSAGE(valid << " texels, " << counts.dropped << " dropped; " << aimed << " rays aimed at the moved ball, " << answered_at_ball
                  << " answered");
    CHECK(aimed > 100);
    CHECK(answered_at_ball == 0);
}

namespace {
// A cube of one texel, holding a point 10 along +z from the centre of the unit box, whose path hit one
// object (key 5) there and nothing else: no light, no further bounce.
std::unique_ptr<CdctCube> one_texel_ten_ahead() {
    auto cube = std::make_unique<CdctCube>(32);
    PathRecord path;
    const glm::vec3 direction = glm::normalize(glm::vec3(0.01f, 0.01f, 1.0f));
    path.hit(5, 10.0f * direction);
    raycache::store_traced(*cube, box, glm::vec3(0.0f), direction, {glm::vec3(0.5f), 10.0f}, parameters, &path);
    cube->begin_frame();
    REQUIRE(cube->valid_texels() == 1);
    return cube;
}
} // namespace

TEST_CASE("CDCT: a sphere beside a texel's stored point, off every segment from the box to it, keeps the texel, one on such a segment drops it") {
    // One texel, holding a point 10 along +z from the centre of the unit box (the segments it answers run
    // from the box's ball, radius sqrt(3), to the shell of its directions at 10 - 0.5 .. 10 + 0.5). Its
    // path hit one object (key 5) there, and nothing else: no light, no further bounce.
    const std::uint64_t mover = 77;
    REQUIRE((raycache::object_bits(5) & raycache::object_bits(mover)) != raycache::object_bits(mover)); // no Bloom alias
    auto after_move = [&](glm::vec3 to, float radius) {
        std::unique_ptr<CdctCube> cube = one_texel_ten_ahead();
        raycache::SceneChanges changes;
        changes.moved.push_back({mover, {glm::vec3(0.0f, 40.0f, 0.0f), radius}, {to, radius}}); // from far away
        const raycache::InvalidationCounts counts = raycache::invalidate_changes(*cube, box, parameters, changes);
        return counts.dropped_by_cone;
    };
    // Beside the stored point: radius 0.5 at (1.8, 0, 10), spanning z 9.5 .. 10.5, at least 1.3 from the z
    // axis. The texel (face coordinates 0 .. 1/16 of the +z face) holds directions within 0.09 rad of +z, so
    // its shell (9.5 .. 10.5 out) lies within 0.95 of the axis, and a segment from the box (within 1.42 of
    // the axis, z <= 1) to it stays within 0.95 + 0.47 x 1.5 / 8.5 < 1.3 of the axis for z >= 9.5: none
    // meets the sphere. The cone from the box's ball would (the sphere lies 0.15 rad off the texel's axis,
    // inside its 0.04 rad spread plus asin((0.5 + 1.73) / 10.2) = 0.22; and 10.2 - 0.5 < 10.5 away).
    CHECK(after_move({1.8f, 0.0f, 10.0f}, 0.5f) == 0);
    // On a segment: from the box's corner (1, 1, 1) to the stored point (0.1, 0.1, 10), the point at z = 8
    // is (0.3, 0.3, 8); a sphere of radius 0.3 around (0.5, 0.5, 8) holds it.
    CHECK(after_move({0.5f, 0.5f, 8.0f}, 0.3f) == 1);
    // Behind the stored surface (z 11.5 .. 12.5: past 10 + 0.5), in line with it: kept, as before.
    CHECK(after_move({0.1f, 0.1f, 12.0f}, 0.5f) == 0);
    // Between the box and the stored point, on the texel's axis: met.
    CHECK(after_move({0.0f, 0.0f, 3.0f}, 0.5f) == 1);
}

TEST_CASE("CDCT: a block whose texels' rays all end short of a sphere in its directions keeps them without testing each texel") {
    // The texel ten ahead lies in a 2 x 2 block of face coordinates within 0.125 of the +z face's centre:
    // directions within atan(0.125 sqrt 2) = 0.18 rad of +z. Its rays end on the shell 9.5 .. 10.5 out, so
    // every segment from the box (z <= 1) to the ends of the block's rays has z <= 10.5.
    auto after_move = [](glm::vec3 to, float radius) {
        std::unique_ptr<CdctCube> cube = one_texel_ten_ahead();
        raycache::SceneChanges changes;
        changes.moved.push_back({77, {glm::vec3(0.0f, 40.0f, 0.0f), radius}, {to, radius}}); // from far away
        return raycache::invalidate_changes(*cube, box, parameters, changes);
    };
    // Behind the surface on the axis (z 11.5 .. 12.5): the block's cone meets it, its segments do not, so
    // no texel of it is tested (blocks_by_texel counts blocks whose texels were).
    const raycache::InvalidationCounts behind = after_move({0.1f, 0.1f, 12.0f}, 0.5f);
    CHECK(behind.blocks_by_texel == 0);
    CHECK(behind.dropped == 0);
    // Between the box and the surface, on the axis: the block's segments meet it, and then the texel's.
    const raycache::InvalidationCounts between = after_move({0.0f, 0.0f, 3.0f}, 0.5f);
    CHECK(between.blocks_by_texel == 1);
    CHECK(between.dropped_by_cone == 1);
}

TEST_CASE("CDCT: rays known to leave from within 1 of the centre keep a texel that only segments from the box's corners would meet") {
    // The texel of one_texel_ten_ahead() (a point 10 along +z). Its segments start from the ball of origins: the
    // box's, radius sqrt(3) = 1.73, or, when the cube answers only rays from within 1 of the centre (the
    // unit sphere's own rays), radius 1. Its shell at 9.5 .. 10.5 lies within 0.95 of the z axis, so the
    // hull of the two balls stays within max(1, 0.95) = 1 of the axis from z = 0 on (a tangent line between
    // two balls lies within the larger radius), plus the test's 0.3% and 0.002 of margin; with the box's
    // ball it reaches 1.73 - (1.73 - 0.95) x 2 / 10 = 1.57 at z = 2. A sphere of radius 0.15 at (1.35, 0,
    // 2) spans 1.2 .. 1.5 from the axis: between the two.
    auto dropped_with_radius = [&](float origin_radius) {
        std::unique_ptr<CdctCube> cube = one_texel_ten_ahead();
        raycache::SceneChanges changes;
        changes.moved.push_back({77, {glm::vec3(0.0f, 40.0f, 0.0f), 0.15f}, {glm::vec3(1.35f, 0.0f, 2.0f), 0.15f}});
        return raycache::invalidate_changes(*cube, raycache::CubeRays{box, -1.0f, origin_radius}, parameters, changes).dropped;
    };
    CHECK(dropped_with_radius(1.0f) == 0);
    CHECK(dropped_with_radius(std::numeric_limits<float>::infinity()) == 1); // the box's ball, as before
    CHECK(dropped_with_radius(5.0f) == 1);                                   // wider than the box: its ball
    CHECK(dropped_with_radius(1.3f) == 1); // from 1.3 out, segments pass 1.3 - 0.035 x 2 = 1.23 > 1.2 off the axis
}

TEST_CASE("CDCT: every search answer that was right before a move is right after exact invalidation, or the search misses") {
    // The oracle of the searches themselves, not of straight segments: fresh rays from the mirror ball are
    // looked up before and after the move. An answer counts as right when its colour is the traced colour
    // (within the texel encoding's rounding); one right before must, after exact invalidation, be right in
    // the moved world or become a miss. The check can fail: a ray answered right before whose traced colour
    // the move changed (`changed`) would, without invalidation, get the same answer, now wrong.
    const World before = make_world();
    const float tolerance = 0.02f; // colour units; the RGB9E5 rounding of colours up to 1 is under 1/256
    auto wrong = [&](const glm::vec3& answer, const glm::vec3& truth) {
        return glm::any(glm::greaterThan(glm::abs(answer - truth), glm::vec3(tolerance)));
    };
    // The oracle's moves, and two larger ones: ball 4 rising by 0.6, and ball 0 coming close to the mirror,
    // where it blocks many of the rays the cube answered.
    std::vector<std::pair<std::size_t, World>> moves = test_moves(before);
    moves.push_back({4, before});
    moves.back().second.balls[4].centre += glm::vec3(0.0f, 0.6f, 0.0f);
    moves.push_back({0, before});
    moves.back().second.balls[0].centre = glm::vec3(2.6f, 0.1f, 0.3f);
    for (const raycache::DepthSearch search : {raycache::DepthSearch::secant, raycache::DepthSearch::relief}) {
        for (const auto& [moved, after] : moves) {
            CAPTURE(moved);
            CAPTURE(search == raycache::DepthSearch::secant ? "secant" : "relief");
            raycache::ReliefParameters p = parameters;
            p.search = search;
            CdctCache exact(32, box, p);
            LeavingRays leaving(8);
            for (int k = 0; k < 30000; ++k) {
                const auto [n, d] = leaving.next();
                exact.cached_trace(n, d, [&, n = n, d = d](PathRecord& path) { return before.traced(n, d, &path); });
                if (k % 5000 == 4999) exact.begin_frame();
            }
            exact.begin_frame();
            LeavingRays queries(99);
            std::vector<std::pair<glm::vec3, glm::vec3>> right_before; // rays the cache answered right
            for (int k = 0; k < 20000; ++k) {
                const auto [o, d] = queries.next();
                const raycache::ReliefResult r = exact.lookup(o, d);
                if (r.hit && !wrong(r.color, before.trace(o, d))) right_before.push_back({o, d});
            }
            const raycache::InvalidationCounts counts = raycache::invalidate_changes(exact, move_of(before, after, moved));
            std::size_t changed = 0, still_answered = 0, wrong_after = 0;
            for (const auto& [o, d] : right_before) {
                const glm::vec3 truth = after.trace(o, d);
                changed += wrong(before.trace(o, d), truth);
                const raycache::ReliefResult r = exact.lookup(o, d);
                still_answered += r.hit;
                wrong_after += r.hit && wrong(r.color, truth);
            }
            MESSAGE(right_before.size() << " of 20000 answered right before, " << changed << " of them changed by the move; "
                                        << counts.dropped << " texels dropped; after: " << still_answered << " answered, "
                                        << wrong_after << " wrong");
            CHECK(right_before.size() > 5000);
            CHECK(changed > 0);
            CHECK(wrong_after == 0);
            CHECK(still_answered > right_before.size() / 2); // it keeps answering most of them
        }
    }
}
