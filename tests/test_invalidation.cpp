// Exact invalidation of a CCT cube (raycache/invalidation.hpp) in an analytic world (analytic_world.hpp:
// spheres of distinct colours lit by a point light with shadows, a mirror ball of radius 1 at the origin)
// whose cube is filled with traced rays and their path records. After a sphere moves, an oracle retraces, for every texel still
// valid, rays from random points of the cube's box through random directions of the texel, in the world
// before and after the move: a texel is stale when any of them sees a different colour. `exact` must leave
// no stale texel (and skipping the invalidation must leave some); texels whose cone (computed here
// independently, from angles) and whose 4 x 4 block's paths miss the moved sphere must be kept.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <vector>

#include <glm/glm.hpp>

#include "raycache/adaptive_resolution.hpp"
#include "raycache/cache_cube.hpp"
#include "raycache/cube_face.hpp"
#include "raycache/invalidation.hpp"
#include "raycache/path_record.hpp"
#include "raycache/shared/origin_rule.h"

#include "analytic_world.hpp"
#include "test_random.hpp"

namespace {

using namespace analytic;
using raycache::CctCube;

// Fills a cube as a mirror ball of radius 1 at the origin would: rays from points of its surface into the
// half-space of their normal, traced in `w` with their path records. `stores` rays.
struct StoredRay {
    TexelAddress texel;
    glm::vec3 origin, direction;
};

// Only directions with d.y <= max_up are stored, each path record passed through `edit` first; `rays`,
// when given, gets every ray stored.
template <class Edit>
void fill_edited(CctCube& cube, const World& w, int stores, unsigned seed, float max_up, Edit&& edit, std::vector<StoredRay>* rays) {
    LeavingRays leaving(seed);
    for (int k = 0; k < stores; ++k) {
        const auto [n, d] = leaving.next();
        if (d.y > max_up) continue;
        PathRecord path;
        const glm::vec3 c = w.trace(n, d, &path);
        edit(path);
        if (cube.store(d, c, path) && rays) {
            const raycache::shared::raycache_texel_address a = raycache::shared::raycache_texel_of(d, cube.face_size());
            rays->push_back({{a.face, a.column, a.row}, n, d});
        }
    }
    cube.begin_frame();
}

// fill_edited() with the records as traced.
void fill(CctCube& cube, const World& w, int stores, unsigned seed, float max_up = 1.0f, std::vector<StoredRay>* rays = nullptr) {
    fill_edited(cube, w, stores, seed, max_up, [](PathRecord&) {}, rays);
}

// Valid texels for which some sampled ray sees a different colour in `after` than in `before`.
std::size_t stale_texels(const CctCube& cube, const World& before, const World& after) {
    Sampler s;
    std::size_t stale = 0;
    cube.for_each_valid_texel([&](const TexelAddress& a) {
        for (int k = 0; k < 48; ++k) {
            const glm::vec3 o = s.origin(k), d = s.direction(a, cube.face_size());
            if (glm::any(glm::greaterThan(glm::abs(before.trace(o, d) - after.trace(o, d)), glm::vec3(1e-6f)))) {
                ++stale;
                return;
            }
        }
    });
    return stale;
}

// A path that saw object `key` straight out along +X, at (5, 0, 0): no shadow ray, no bounce.
PathRecord saw(std::uint64_t key) {
    PathRecord path;
    path.hit(key, glm::vec3(5.0f, 0.0f, 0.0f));
    return path;
}

// Stores colour 0.25 with `path` into the square of face +X at columns [first_column, first_column + edge)
// and rows [0, edge), then ends the frame.
void fill_square(CctCube& cube, int first_column, int edge, const PathRecord& path) {
    for (int row = 0; row < edge; ++row)
        for (int column = first_column; column < first_column + edge; ++column)
            REQUIRE(cube.store_at({RAYCACHE_FACE_POSITIVE_X, column, row}, glm::vec3(0.25f), path));
    cube.begin_frame();
}

// Object `key` moving far out along -X (a ball of radius 0.5 around (-20, 0, 0), then (-20, 0.5, 0)),
// where no ray of face +X can reach it: only path records can drop a texel of that face for it.
raycache::SceneChanges far_along_minus_x(std::uint64_t key) {
    raycache::SceneChanges changes;
    changes.moved.push_back({key, {glm::vec3(-20.0f, 0.0f, 0.0f), 0.5f}, {glm::vec3(-20.0f, 0.5f, 0.0f), 0.5f}});
    return changes;
}

} // namespace

TEST_CASE("after a sphere moves, exact invalidation leaves no stale texel, without it the oracle finds them") {
    const World before = make_world();
    for (const auto& [moved, after] : test_moves(before)) {
        CAPTURE(moved);
        CctCube kept(32), exact(32);
        fill(kept, before, 30000, 1);
        fill(exact, before, 30000, 1);
        const std::size_t valid = exact.valid_texels();
        REQUIRE(valid > 4000);

        const std::size_t stale_without = stale_texels(kept, before, after);
        const raycache::InvalidationCounts counts = raycache::invalidate_changes(exact, {box, -1.0f}, move_of(before, after, moved));
        const std::size_t stale_with = stale_texels(exact, before, after);
        MESSAGE("ball " << moved << ": " << valid << " texels, " << stale_without << " stale without invalidation, " << counts.dropped
                        << " dropped by exact (" << counts.blocks_by_path << " blocks by path, " << counts.blocks_by_texel
                        << " tested per texel), " << stale_with << " stale after");
        CHECK(stale_without > 0);
        CHECK(stale_with == 0);
        CHECK(counts.dropped == valid - exact.valid_texels());
        CHECK(counts.dropped < valid / 2); // it keeps most of the cube
    }
}

TEST_CASE("texels whose cone and whose 2 x 2 block's paths miss the moved sphere are kept") {
    const World before = make_world();
    World after = before;
    const std::size_t moved = 3;
    after.balls[moved].centre += glm::vec3(0.0f, 0.3f, 0.0f);
    CctCube cube(32);
    fill(cube, before, 30000, 2);

    // Which 2 x 2 blocks' stored paths met the ball, from the rays themselves (the same seed as fill(), so
    // the same rays): a block whose paths hit the ball, or whose hit points' shadow rays can pass it.
    auto block_of = [](const TexelAddress& a) { return static_cast<std::size_t>((a.face * 16 + a.row / 2) * 16 + a.column / 2); };
    std::vector<char> block_met(6 * 16 * 16, 0);
    {
        LeavingRays leaving(2);
        for (int k = 0; k < 30000; ++k) {
            const auto [n, d] = leaving.next();
            PathRecord path;
            before.trace(n, d, &path);
            const raycache::shared::raycache_texel_address a = raycache::shared::raycache_texel_of(d, 32);
            const bool hit_it = (path.objects & raycache::object_bits(moved)) == raycache::object_bits(moved);
            if (hit_it || path.has_vertices()) // hit points shadowed by it: decided by the block's light cone, so count
                block_met[block_of({a.face, a.column, a.row})] |= hit_it ? 1 : 2;
        }
    }
    // A texel's rays can reach the ball only within this angle of its centre direction: half the texel's
    // diagonal (< 3 degrees at 32 texels) plus the ball's angular radius seen with the box's ball added.
    auto clearly_away = [&](const TexelAddress& a, const Ball& b) {
        const glm::vec3 d = glm::normalize(raycache::texel_direction(a, 32));
        const float dist = glm::length(b.centre);
        const float cap = std::asin(std::min(1.0f, (b.radius + 1.7321f) / dist));
        const float angle = std::acos(glm::clamp(glm::dot(d, b.centre / dist), -1.0f, 1.0f));
        return angle > cap + 3.0f * 3.14159265f / 180.0f;
    };
    std::vector<TexelAddress> must_keep;
    cube.for_each_valid_texel([&](const TexelAddress& a) {
        if (block_met[block_of(a)] & 1) return;
        if (clearly_away(a, before.balls[moved]) && clearly_away(a, after.balls[moved])) must_keep.push_back(a);
    });
    const std::size_t valid = cube.valid_texels();
    const raycache::InvalidationCounts counts = raycache::invalidate_changes(cube, {box, -1.0f}, move_of(before, after, moved));
    std::size_t kept = 0, lost_to_light_cone = 0;
    for (const TexelAddress& a : must_keep) {
        if (cube.load(a)) ++kept;
        else {
            // The only other reason: its block's shadow rays may pass the ball (block_met bit 2); check that
            // the light cone test really is what dropped it.
            REQUIRE((block_met[block_of(a)] & 2));
            ++lost_to_light_cone;
        }
    }
    MESSAGE(valid << " texels, " << must_keep.size() << " clearly away from the ball's cone and paths; " << kept << " kept, "
                  << lost_to_light_cone << " dropped whole with blocks whose shadow rays may pass it; " << counts.dropped << " dropped in all");
    CHECK(must_keep.size() > 1000);
    CHECK(kept > must_keep.size() / 2);
}

TEST_CASE("a path that hit a moved object costs the texels of its 2 x 2 record block, not the rest of its tile") {
    // Face +X of a 16-texel cube is one tile of sixty-four 2 x 2 blocks. Block 0 (columns and rows 0..1) holds
    // paths that hit object 5, the other blocks paths that hit object 6; object 5 moves far out along -X,
    // where no ray of face +X can reach it, so only the path records can drop anything.
    REQUIRE((raycache::object_bits(6) & raycache::object_bits(5)) != raycache::object_bits(5));
    CctCube cube(16);
    const PathRecord saw_5 = saw(5), saw_6 = saw(6);
    for (int row = 0; row < 16; ++row)
        for (int column = 0; column < 16; ++column)
            REQUIRE(cube.store_at({RAYCACHE_FACE_POSITIVE_X, column, row}, glm::vec3(0.25f), column < 2 && row < 2 ? saw_5 : saw_6));
    cube.begin_frame();
    const raycache::SceneChanges changes = far_along_minus_x(5);
    const raycache::InvalidationCounts counts = raycache::invalidate_changes(cube, {box, -1.0f}, changes);
    CHECK(counts.dropped == 4);
    CHECK(counts.dropped_by_path == 4); // the reason, counted: no cone reaches -X, every store recorded
    CHECK(counts.dropped_by_cone + counts.dropped_unrecorded == 0);
    CHECK(counts.blocks_by_path == 1);
    CHECK(cube.valid_texels() == 256 - 4);
    for (int row = 0; row < 16; ++row)
        for (int column = 0; column < 16; ++column)
            CHECK(cube.load({RAYCACHE_FACE_POSITIVE_X, column, row}).has_value() == !(column < 2 && row < 2));
}

TEST_CASE("a tile that no change can reach is passed over without reading its blocks, and a tile a move emptied forgets its paths") {
    // Face +X of a 32-texel cube has four 16 x 16 tiles. The first tile's texels saw object 5, the second's
    // object 6, all at (5, 0, 0); object 5 moves far out along -X, where no ray of face +X can reach it. Only
    // the first tile's union names 5, so only its 64 blocks are read, and its 256 texels go. Refilled with
    // paths that saw object 6, the first tile must be passed over at 5's next move too: its union was
    // rebuilt from what its blocks kept (nothing), not left holding 5.
    REQUIRE((raycache::object_bits(6) & raycache::object_bits(5)) != raycache::object_bits(5));
    CctCube cube(32);
    const PathRecord saw_5 = saw(5), saw_6 = saw(6);
    auto fill_tile = [&](int first_column, const PathRecord& path) { fill_square(cube, first_column, 16, path); };
    fill_tile(0, saw_5);
    fill_tile(16, saw_6);
    const raycache::SceneChanges changes = far_along_minus_x(5);
    const raycache::InvalidationCounts first = raycache::invalidate_changes(cube, {box, -1.0f}, changes);
    CHECK(first.dropped == 256);
    CHECK(first.blocks == static_cast<std::size_t>(CctCube::record_blocks)); // the first tile's alone
    fill_tile(0, saw_6);
    const raycache::InvalidationCounts second = raycache::invalidate_changes(cube, {box, -1.0f}, changes);
    CHECK(second.dropped == 0);
    CHECK(second.blocks == 0u);
    CHECK(cube.valid_texels() == 512);
}

TEST_CASE("a 4 x 4 group a move emptied forgets its paths, and a group that lost nothing keeps its union") {
    // Tile 0 of face +X: the first group (columns 0-3, rows 0-3) saw object 5, the second (columns 4-7) object
    // 6. Object 5 moves where no ray of +X reaches: the first group's 16 texels go by path, and its union,
    // rebuilt from what its blocks kept, is empty; the second's still names 6 alone, and so does the tile's.
    // Refilled with paths that saw 6, the first group names 6 and not 5.
    REQUIRE((raycache::object_bits(6) & raycache::object_bits(5)) != raycache::object_bits(5));
    CctCube cube(32);
    const PathRecord saw_5 = saw(5), saw_6 = saw(6);
    auto fill_group = [&](int first_column, const PathRecord& path) { fill_square(cube, first_column, 4, path); };
    fill_group(0, saw_5);
    fill_group(4, saw_6);
    CHECK(cube.group_keys(0, 0).objects == raycache::object_bits(5));
    const raycache::InvalidationCounts moved = raycache::invalidate_changes(cube, {box, -1.0f}, far_along_minus_x(5));
    CHECK(moved.dropped == 16);
    CHECK(cube.group_keys(0, 0).objects == 0u);
    CHECK_FALSE(cube.group_keys(0, 0).record().has_vertices());
    CHECK(cube.group_keys(0, 1).objects == raycache::object_bits(6));
    CHECK(cube.tile_paths(0)->objects == raycache::object_bits(6));
    fill_group(0, saw_6);
    CHECK(cube.group_keys(0, 0).objects == raycache::object_bits(6));
    CHECK(cube.valid_texels() == 32);
}

TEST_CASE("merging a path whose escapes have no hit point before them with one that has hit points leaves it unbounded") {
    // A path that hit object 7 at (5, 0, 0) and stopped, and one that escaped along +X with no hit recorded
    // before it. Merged either way round, the escape would seem to leave (5, 0, 0), from where nothing
    // reaches object 9 far out along -X; the merged record must say it has no bound. A bounce recorded after
    // its hit point merges as before.
    PathRecord stopped, loose, bounced;
    stopped.hit(7, glm::vec3(5.0f, 0.0f, 0.0f));
    loose.escaped(glm::vec3(1.0f, 0.0f, 0.0f));
    bounced.hit(7, glm::vec3(5.0f, 0.0f, 0.0f));
    bounced.escaped(glm::vec3(0.0f, 0.0f, 1.0f));
    PathRecord a = stopped, b = loose, c = stopped;
    a.merge(loose);
    b.merge(stopped);
    c.merge(bounced);
    CHECK(a.unbounded);
    CHECK(b.unbounded);
    CHECK_FALSE(c.unbounded);
    const raycache::SceneChanges changes = far_along_minus_x(9);
    CHECK(raycache::detail::paths_meet(a, changes));
    CHECK(raycache::detail::paths_meet(b, changes));
    CHECK_FALSE(raycache::detail::paths_meet(c, changes));
}

TEST_CASE("shadow rays end at the light: a sphere moving beyond the lit hit points is not met, one between them and the light is") {
    // A path lit at (5, 0, 0) by a light at (15, 0, 0): its shadow ray is the segment x 5 .. 15 on the X axis.
    // Object 9 moves along Y by 0.5, radius 0.5, around x = -5 (beyond the hit point, seen from the light: in
    // the light's cone over the hit point but on no shadow ray), around x = 10 (on the shadow ray), or around
    // (10, 3) (beside it).
    REQUIRE((raycache::object_bits(7) & raycache::object_bits(9)) != raycache::object_bits(9)); // no Bloom alias
    PathRecord lit = saw(7);
    lit.lit = true;
    auto moving_around = [](glm::vec3 centre) {
        raycache::SceneChanges changes;
        changes.moved.push_back({9, {centre, 0.5f}, {centre + glm::vec3(0.0f, 0.5f, 0.0f), 0.5f}});
        changes.lights.push_back(glm::vec3(15.0f, 0.0f, 0.0f));
        return changes;
    };
    CHECK(raycache::detail::paths_meeting(lit, moving_around({-5.0f, 0.0f, 0.0f})) == 0u);
    CHECK(raycache::detail::paths_meeting(lit, moving_around({10.0f, 0.0f, 0.0f})) == raycache::detail::path_test_shadow);
    CHECK(raycache::detail::paths_meeting(lit, moving_around({10.0f, 3.0f, 0.0f})) == 0u);
}

TEST_CASE("bounces between hit points leave from points offset from them: a sphere within the offset of their box is met") {
    // A chained path between hit points (0, 0, 0) and (10, 0, 0): the tracer may start a bounce up to
    // 1e-3 x 10 = 0.01 off a hit point, so the bounce from (10, 0.009, 0) back to (0, 0, 0) passes (5, 0.0045,
    // 0), 0.9995 from (5, 1.004, 0): a sphere of radius 1 there, 0.004 off the box, meets it. At (5, 1.05, 0)
    // it is 0.05 off, beyond any offset, and is not met.
    REQUIRE((raycache::object_bits(7) & raycache::object_bits(9)) != raycache::object_bits(9)); // no Bloom alias
    PathRecord chain;
    chain.hit(7, glm::vec3(0.0f));
    chain.hit(7, glm::vec3(10.0f, 0.0f, 0.0f));
    chain.chained = true;
    auto moving_around = [](glm::vec3 centre) {
        raycache::SceneChanges changes;
        changes.moved.push_back({9, {centre, 1.0f}, {centre + glm::vec3(0.0f, 0.0f, 0.5f), 1.0f}});
        return changes;
    };
    using namespace raycache::detail;
    CHECK(paths_meeting(chain, moving_around({5.0f, 1.004f, 0.0f})) == path_test_between);
    CHECK(paths_meeting(chain, moving_around({5.0f, 1.05f, 0.0f})) == 0u);
}

TEST_CASE("the shadow test never misses a sampled shadow ray that meets a moved sphere") {
    // Random lit unions (a box of hit points, flat along an axis in a third of the cases), lights, and moved
    // spheres placed about a random shadow ray, on it or near it. Shadow rays leave points of the box moved
    // by up to the surface offset the tracer may add (1e-3 x max(1, |point|)) and end at the light; whenever
    // a sampled one meets a sphere, the shadow test must report it.
    Lcg random{31};
    auto uniform = [&](float lo, float hi) { return lo + (hi - lo) * random.uniform(); };
    auto in_box = [&](glm::vec3 lo, glm::vec3 size) { return lo + glm::vec3(random.uniform(), random.uniform(), random.uniform()) * size; };
    int segments_met = 0, unions_met = 0;
    constexpr int trials = 400;
    for (int trial = 0; trial < trials; ++trial) {
        const glm::vec3 lo(uniform(-40.0f, 40.0f), uniform(-40.0f, 40.0f), uniform(-40.0f, 40.0f));
        glm::vec3 size(uniform(0.0f, 15.0f), uniform(0.0f, 15.0f), uniform(0.0f, 15.0f));
        if (trial % 3 == 0) size[trial % 2] = 0.0f;
        PathRecord u;
        u.hit(7, lo);
        u.hit(7, lo + size);
        u.lit = true;
        const glm::vec3 light(uniform(-30.0f, 30.0f), uniform(-30.0f, 30.0f), uniform(-30.0f, 30.0f));
        // About a point of a shadow ray, within a few radii of it.
        const float r0 = uniform(0.1f, 3.0f), r1 = uniform(0.1f, 3.0f);
        const glm::vec3 on = glm::mix(in_box(lo, size), light, random.uniform());
        const glm::vec3 c = on + 2.0f * r0 * glm::vec3(random.signed_uniform(), random.signed_uniform(), random.signed_uniform());
        raycache::SceneChanges changes;
        changes.moved.push_back({9, {c, r0}, {c + glm::vec3(uniform(-2.0f, 2.0f), 0.0f, 0.0f), r1}});
        changes.lights.push_back(light);
        const bool said = raycache::detail::paths_meeting(u, changes, raycache::detail::path_test_shadow) != 0u;
        unions_met += said;
        for (int k = 0; k < 400; ++k) {
            glm::vec3 p = in_box(lo, size);
            if (k % 4 == 0) p = glm::vec3(k & 8 ? lo.x + size.x : lo.x, k & 16 ? lo.y + size.y : lo.y, k & 32 ? lo.z + size.z : lo.z);
            p += 1e-3f * std::max(1.0f, glm::length(p)) * 0.57f * glm::vec3(random.signed_uniform(), random.signed_uniform(), random.signed_uniform());
            for (const raycache::BoundingSphere& s : {changes.moved[0].before, changes.moved[0].after}) {
                const glm::vec3 d = light - p;
                const float t = glm::dot(d, d) > 0.0f ? glm::clamp(glm::dot(s.centre - p, d) / glm::dot(d, d), 0.0f, 1.0f) : 0.0f;
                const glm::vec3 x = p + t * d - s.centre;
                if (glm::dot(x, x) <= s.radius * s.radius) {
                    ++segments_met;
                    REQUIRE(said);
                }
            }
        }
    }
    MESSAGE(unions_met << " of " << trials << " unions met; " << segments_met << " sampled shadow rays met a sphere");
    CHECK(segments_met > 1000);
    CHECK(unions_met < trials * 9 / 10); // and the test does reject
}

TEST_CASE("the path tests report every test that met, repeat only the tests asked for, and can stop at the first") {
    // A lit path that hit object 9 at (5, 0, 0) and bounced on to (6, 0, 0); object 9 moves by 0.5 along Y,
    // radius 0.5, around (10, 0, 0): on the shadow rays to the light at (15, 0, 0), off the hit points' box.
    PathRecord path = saw(9);
    path.hit(9, glm::vec3(6.0f, 0.0f, 0.0f));
    path.lit = true;
    path.chained = true;
    raycache::SceneChanges changes;
    changes.moved.push_back({9, {glm::vec3(10.0f, 0.0f, 0.0f), 0.5f}, {glm::vec3(10.0f, 0.5f, 0.0f), 0.5f}});
    changes.lights.push_back(glm::vec3(15.0f, 0.0f, 0.0f));
    using namespace raycache::detail;
    CHECK(paths_meeting(path, changes) == (path_test_moved | path_test_shadow));
    CHECK(paths_meeting(path, changes, path_test_shadow | path_test_between) == path_test_shadow);
    CHECK(paths_meeting(path, changes, path_test_between | path_test_escape) == 0u);
    CHECK(paths_meeting(path, changes, every_path_test, true) == path_test_moved); // the first in order
}

TEST_CASE("a changed cached object meets a path only where the path's cached answers read its cube") {
    // A path hit cached object 4 at (5, 0, 0), whose cube answered its bounce toward +z (+Z's centre
    // cell). Object 4's cube lost texels: in +Z's centre cell, it meets; only on +X, it does not; as a
    // whole (every cell), it does. A path that did not track its cached reads meets wherever 4 changed.
    using namespace raycache::detail;
    PathRecord tracked = saw(4);
    tracked.track_cached_reads();
    tracked.read_cached(glm::vec3(0, 0, 1), glm::vec3(0, 0, 1));
    const PathRecord untracked = saw(4);
    auto changed = [](std::uint64_t cells) {
        raycache::SceneChanges c;
        c.changed.push_back({4, cells});
        return c;
    };
    const std::uint64_t plus_x = raycache::direction_cells_of_box(glm::vec3(1, -1, -1), glm::vec3(1, 1, 1)); // all of +X
    CHECK(paths_meeting(tracked, changed(raycache::direction_cell_bit(4, 1, 1))) == path_test_changed);
    CHECK(paths_meeting(tracked, changed(plus_x)) == 0u);
    CHECK(paths_meeting(tracked, changed(raycache::every_direction_cell)) == path_test_changed);
    CHECK(paths_meeting(untracked, changed(plus_x)) == path_test_changed);
    // Another object's change in the cell the path read: not this path's (its mask names 4 alone).
    REQUIRE((raycache::object_bits(4) & raycache::object_bits(5)) != raycache::object_bits(5));
    raycache::SceneChanges other;
    other.changed.push_back({5, raycache::direction_cell_bit(4, 1, 1)});
    CHECK(paths_meeting(tracked, other) == 0u);
    // Both listed: the one the path read where it changed meets.
    other.changed.push_back({4, raycache::direction_cell_bit(4, 1, 1)});
    CHECK(paths_meeting(tracked, other) == path_test_changed);
}

TEST_CASE("a union in key form meets the changes its record meets, and changes that move nothing without decoding") {
    // paths_meeting_keys() answers from the keys a tile keeps (CacheCube::PathKeys). Hand cases for changes
    // that move nothing (a transitive pass's: cached object 4's cube lost texels everywhere), where only
    // the unbound and changed tests can meet; then random unions, boxes empty, ordered, inverted or holding
    // NaN keys, against paths_meeting() of the records they decode to, for every set of tests, first only
    // or not, with and without moves and a moved light.
    using namespace raycache::detail;
    using Keys = CctCube::PathKeys;
    const auto key = [](float f) { return raycache::shared::raycache_ordered_key(f); };
    const std::uint32_t nan_key = key(std::numeric_limits<float>::quiet_NaN());
    auto box = [&](std::uint32_t (&min)[3], std::uint32_t (&max)[3], float lo, float hi) {
        for (int k = 0; k < 3; ++k) min[k] = key(lo), max[k] = key(hi);
    };
    raycache::SceneChanges mirror;
    mirror.changed.push_back({4});

    const Keys empty = Keys::empty();
    CHECK(paths_meeting_keys(empty, mirror, every_path_test, false) == 0u);
    Keys escapes_only = Keys::empty(); // escapes with no hit point before them: no bound on where they went
    box(escapes_only.escape_min, escapes_only.escape_max, -0.5f, 0.5f);
    CHECK(paths_meeting_keys(escapes_only, mirror, every_path_test, false) == path_test_unbound);
    Keys flagged = Keys::empty();
    flagged.flags = CctCube::path_unbounded;
    CHECK(paths_meeting_keys(flagged, mirror, every_path_test, false) == path_test_unbound);
    CHECK(paths_meeting_keys(flagged, mirror, every_path_test & ~path_test_unbound, false) == 0u);
    Keys saw_mirror = Keys::empty(); // hit object 4 and escaped: bounded, and read 4's cube everywhere
    box(saw_mirror.vertex_min, saw_mirror.vertex_max, 1.0f, 2.0f);
    box(saw_mirror.escape_min, saw_mirror.escape_max, -0.5f, 0.5f);
    saw_mirror.objects = raycache::object_bits(4);
    saw_mirror.cached_reads = raycache::every_direction_cell;
    CHECK(paths_meeting_keys(saw_mirror, mirror, every_path_test, false) == path_test_changed);
    saw_mirror.cached_reads = 0; // read no cube: whatever it hit, no cube's change reaches it
    CHECK(paths_meeting_keys(saw_mirror, mirror, every_path_test, false) == 0u);
    saw_mirror.cached_reads = raycache::every_direction_cell;
    saw_mirror.flags = CctCube::path_unbounded; // both tests meet; the first in order alone when the caller stops there
    CHECK(paths_meeting_keys(saw_mirror, mirror, every_path_test, false) == (path_test_unbound | path_test_changed));
    CHECK(paths_meeting_keys(saw_mirror, mirror, every_path_test, true) == path_test_unbound);
    // Keys in order whose upper x decodes to NaN hold no hit point as the record decodes them, so these
    // escapes have none before them.
    Keys nan_vertices = escapes_only;
    box(nan_vertices.vertex_min, nan_vertices.vertex_max, 0.0f, 1.0f);
    nan_vertices.vertex_max[0] = nan_key;
    REQUIRE(nan_vertices.vertex_min[0] <= nan_vertices.vertex_max[0]);
    CHECK_FALSE(nan_vertices.has_vertices());
    CHECK(paths_meeting_keys(nan_vertices, mirror, every_path_test, false) == path_test_unbound);

    Lcg rng{20261204};
    auto random_box = [&](std::uint32_t (&min)[3], std::uint32_t (&max)[3]) {
        const std::uint32_t kind = rng.next() % 5;
        for (int k = 0; k < 3; ++k) {
            float a = 20.0f * rng.signed_uniform(), b = 20.0f * rng.signed_uniform();
            if (kind == 0) min[k] = ~0u, max[k] = 0u;                          // empty
            else if (kind == 1) min[k] = key(std::min(a, b)), max[k] = key(std::max(a, b)); // a box
            else if (kind == 2) min[k] = key(std::max(a, b)), max[k] = key(std::min(a, b)); // inverted
            else if (kind == 3) min[k] = rng.next(), max[k] = rng.next();       // any bits
            else min[k] = key(std::min(a, b)), max[k] = (rng.next() & 1u) ? nan_key : key(std::max(a, b));
        }
    };
    int compared = 0, differing = 0;
    for (int u = 0; u < 3000; ++u) {
        Keys k = Keys::empty();
        k.objects = (static_cast<std::uint64_t>(rng.next()) << 32) | rng.next();
        if (rng.next() % 4 == 0) k.objects = raycache::object_bits(rng.next() % 16);
        k.cached_reads = rng.next() % 3 == 0 ? 0 : (rng.next() % 2 ? raycache::every_direction_cell : (static_cast<std::uint64_t>(rng.next()) << 22) ^ rng.next());
        k.flags = rng.next() % 8;
        random_box(k.vertex_min, k.vertex_max);
        random_box(k.escape_min, k.escape_max);
        raycache::SceneChanges c;
        for (std::uint32_t n = rng.next() % 4; n > 0; --n)
            c.changed.push_back({rng.next() % 16, rng.next() % 2 ? raycache::every_direction_cell : (static_cast<std::uint64_t>(rng.next()) << 22) ^ rng.next()});
        if (rng.next() % 2) {
            const glm::vec3 at(10.0f * rng.signed_uniform(), 10.0f * rng.signed_uniform(), 10.0f * rng.signed_uniform());
            c.moved.push_back({rng.next() % 16, {at, 2.0f * rng.uniform()}, {at + glm::vec3(1.0f, 0.0f, 0.0f), 2.0f * rng.uniform()}});
            c.lights.push_back(glm::vec3(0.0f, 30.0f, 0.0f));
        }
        c.light_moved = rng.next() % 8 == 0;
        const raycache::PathRecord record = k.record();
        for (unsigned tests = 0; tests <= every_path_test; ++tests)
            for (bool first_only : {false, true}) {
                ++compared;
                differing += paths_meeting_keys(k, c, tests, first_only) != paths_meeting(record, c, tests, first_only);
            }
    }
    CHECK(compared == 3000 * 128 * 2);
    CHECK(differing == 0);
}

TEST_CASE("a pass reports the direction cells of the texels it emptied, each grown by a texel") {
    // Two texels of face +X of a 16-texel cube, each in a block of its own: (1, 1) (sc, tc near -1: its
    // block's texels 0..1, grown to -1..2, span sc and tc in [-1.125, -0.625]: cell (0, 0) of +X, and over
    // the face's edges the cells of +Y and +Z touching that corner) saw object 9, which moves far along -X;
    // (8, 8) (the centre cell) saw object 7, which stays. Only the first goes, and only its cells are named.
    CctCube cube(16);
    REQUIRE(cube.store_at({RAYCACHE_FACE_POSITIVE_X, 1, 1}, glm::vec3(0.25f), saw(9)));
    REQUIRE(cube.store_at({RAYCACHE_FACE_POSITIVE_X, 8, 8}, glm::vec3(0.25f), saw(7)));
    cube.begin_frame();
    const raycache::InvalidationCounts counts = raycache::invalidate_changes(cube, {box, -1.0f}, far_along_minus_x(9));
    CHECK(counts.dropped == 1);
    // +X (face 0): sc = -z, tc = -y near -1, so the corner direction (1, 1, 1); its cells on +Y (2): sc = x,
    // tc = z near +1: (2, 2); on +Z (4): sc = x near 1, tc = -y near -1: (2, 0).
    const std::uint64_t corner = raycache::direction_cell_bit(0, 0, 0) | raycache::direction_cell_bit(2, 2, 2) | raycache::direction_cell_bit(4, 2, 0);
    CHECK(counts.changed_cells == corner);
}

TEST_CASE("a block whose paths include escapes with no hit point to start from goes at any move") {
    // Two texels of one 2 x 2 block of face +X: one path hit object 7 at (5, 0, 0) and stopped, the other
    // escaped along +X with no hit recorded before it (no bound on where it started). Object 9 moves far out
    // along -X: from (5, 0, 0) nothing escaping along +X can reach it, but the second path could have started
    // anywhere, so the block goes (a union that took the escape as leaving the first path's hit point would
    // keep it).
    CctCube cube(16);
    PathRecord stopped, unbound;
    stopped.hit(7, glm::vec3(5.0f, 0.0f, 0.0f));
    unbound.escaped(glm::vec3(1.0f, 0.0f, 0.0f));
    REQUIRE(cube.store_at({RAYCACHE_FACE_POSITIVE_X, 0, 0}, glm::vec3(0.25f), stopped));
    REQUIRE(cube.store_at({RAYCACHE_FACE_POSITIVE_X, 1, 0}, glm::vec3(0.25f), unbound));
    cube.begin_frame();
    const raycache::SceneChanges changes = far_along_minus_x(9);
    const raycache::InvalidationCounts counts = raycache::invalidate_changes(cube, {box, -1.0f}, changes);
    CHECK(counts.dropped == 2);
    CHECK(counts.dropped_by_path == 2);
}

TEST_CASE("a block emptied by a move forgets the paths it held: refilled with paths that missed the mover, it stays at the next move") {
    // Blocks 0, 1, 8 and 9 of face +X (columns and rows 0..3) first hold paths that hit object 5, which moves (far out
    // along -X, where no ray of face +X can reach it): the blocks go. Refilled with paths that hit object 6
    // only, they must survive object 5's next move; a record that still held the first paths would drop them.
    // A texel stored without a record at (10, 10), in the same tile, goes at every move; it keeps the tile
    // from being passed over whole, so the blocks' own records are what decides.
    REQUIRE((raycache::object_bits(6) & raycache::object_bits(5)) != raycache::object_bits(5));
    CctCube cube(16);
    const PathRecord saw_5 = saw(5), saw_6 = saw(6);
    auto fill_block = [&](const PathRecord& path) {
        for (int row = 0; row < 4; ++row)
            for (int column = 0; column < 4; ++column) REQUIRE(cube.store_at({RAYCACHE_FACE_POSITIVE_X, column, row}, glm::vec3(0.25f), path));
        REQUIRE(cube.store_at({RAYCACHE_FACE_POSITIVE_X, 10, 10}, glm::vec3(0.25f)));
        cube.begin_frame();
    };
    const raycache::SceneChanges changes = far_along_minus_x(5);
    fill_block(saw_5);
    CHECK(raycache::invalidate_changes(cube, {box, -1.0f}, changes).dropped == 17);
    CHECK(cube.valid_texels() == 0);
    fill_block(saw_6);
    const raycache::InvalidationCounts again = raycache::invalidate_changes(cube, {box, -1.0f}, changes);
    CHECK(again.valid_before == 17);
    CHECK(again.dropped == 1);
    CHECK(again.dropped_unrecorded == 1);
    CHECK(again.blocks > 0u); // the tile was read
    CHECK(cube.valid_texels() == 16);
}

TEST_CASE("blocks of one 4 x 4 group are judged by their own paths when only the group's union meets the move") {
    // Face +Y of a 16-texel cube: block 0 (columns and rows 0..1) holds paths that hit a point P = (0, 5, 0)
    // and escaped straight along +X, block 1 (columns 2..3) paths from P that escaped along +Z; the other
    // blocks hold no path. A ball of radius 0.5 moves to P + 10 (1, 0, 1) / sqrt(2): 45 degrees off either
    // escape, 10 away, so it subtends under 3 degrees and neither block's escaped rays (from within the
    // tracer's 1e-3 offset of P) can meet it; the two blocks' union, the escape directions' box from +X to
    // +Z, holds its direction. The texels' own rays go up and toward -X and -Z (face +Y's first rows and
    // columns), away from the ball. So nothing may go; with the group's union alone both blocks (8 texels)
    // would.
    CctCube cube(16);
    const glm::vec3 p(0.0f, 5.0f, 0.0f);
    PathRecord along_x, along_z;
    along_x.hit(7, p);
    along_x.escaped(glm::vec3(1.0f, 0.0f, 0.0f));
    along_z.hit(7, p);
    along_z.escaped(glm::vec3(0.0f, 0.0f, 1.0f));
    for (int row = 0; row < 2; ++row)
        for (int column = 0; column < 4; ++column)
            REQUIRE(cube.store_at({RAYCACHE_FACE_POSITIVE_Y, column, row}, glm::vec3(0.25f), column < 2 ? along_x : along_z));
    cube.begin_frame();
    const glm::vec3 away = p + 10.0f * glm::normalize(glm::vec3(1.0f, 0.0f, 1.0f));
    // The union's cone does hold the ball: the premise of the test (tested on one record of both escapes).
    PathRecord both = along_x;
    both.merge(along_z);
    raycache::SceneChanges changes;
    changes.moved.push_back({9, {glm::vec3(0.0f, -40.0f, 0.0f), 0.5f}, {away, 0.5f}});
    REQUIRE(raycache::detail::paths_meet(both, changes));
    REQUIRE_FALSE(raycache::detail::paths_meet(along_x, changes));
    REQUIRE_FALSE(raycache::detail::paths_meet(along_z, changes));
    const raycache::InvalidationCounts counts = raycache::invalidate_changes(cube, {box, -1.0f}, changes);
    CHECK(counts.valid_before == 8);
    CHECK(counts.dropped == 0);
    CHECK(counts.blocks_by_path == 0);
    CHECK(cube.valid_texels() == 8);
}

TEST_CASE("a moved light drops every texel whose path hit something and keeps the rays that escaped") {
    const World w = make_world();
    CctCube cube(16);
    fill(cube, w, 8000, 4);
    std::size_t sky = 0;
    Sampler s;
    cube.for_each_valid_texel([&](const TexelAddress& a) { sky += *cube.load(a) == glm::vec3(0.0f); });
    raycache::SceneChanges changes;
    changes.light_moved = true;
    changes.lights.push_back(w.light + glm::vec3(1.0f, 0.0f, 0.0f));
    const raycache::InvalidationCounts counts = raycache::invalidate_changes(cube, {box, -1.0f}, changes);
    std::size_t remaining_lit = 0;
    cube.for_each_valid_texel([&](const TexelAddress& a) { remaining_lit += *cube.load(a) != glm::vec3(0.0f); });
    CHECK(remaining_lit == 0);
    CHECK(cube.valid_texels() > 0);
    CHECK(cube.valid_texels() <= sky); // whole blocks with a hit go, so at most the sky texels stay
    CHECK(counts.dropped + cube.valid_texels() == counts.valid_before);
}

TEST_CASE("texels stored without a path record are dropped by any move, recorded ones far from it are kept") {
    const World w = make_world();
    CctCube cube(16);
    // A recorded store and an unrecorded one, on opposite sides, far from every ball's path (sky upwards).
    const glm::vec3 up(0.0f, 1.0f, 0.0f), down(0.0f, -1.0f, 0.0f);
    cube.store(up, glm::vec3(0.5f), PathRecord{});
    cube.store(down, glm::vec3(0.5f));
    cube.begin_frame();
    raycache::SceneChanges changes;
    changes.moved.push_back({99, {glm::vec3(20.0f, 0.0f, 0.0f), 0.5f}, {glm::vec3(20.0f, 0.5f, 0.0f), 0.5f}});
    const raycache::InvalidationCounts counts = raycache::invalidate_changes(cube, {box, -1.0f}, changes);
    CHECK(counts.dropped == 1);
    CHECK(counts.dropped_unrecorded == 1);
    CHECK(counts.dropped_by_path + counts.dropped_by_cone == 0);
    CHECK(cube.peek(up).has_value());
    CHECK(!cube.peek(down).has_value());
}

TEST_CASE("a cube without path records counts every store as unrecorded: any move drops it, resampling carries nothing") {
    CctCube cube(16, nullptr, false);
    const glm::vec3 up(0.0f, 1.0f, 0.0f), down(0.0f, -1.0f, 0.0f);
    PathRecord saw;
    saw.hit(7, glm::vec3(0.0f, 5.0f, 0.0f));
    CHECK(cube.store(up, glm::vec3(0.5f), saw));
    CHECK(cube.store(down, glm::vec3(0.5f)));
    cube.begin_frame();
    int blocks_with_values = 0;
    cube.for_each_block_state([&](const CctCube::BlockState& b) {
        CHECK(b.objects == 0u); // no union kept
        CHECK(b.unrecorded_texels == b.valid_texels);
        blocks_with_values += b.valid_texels > 0;
    });
    CHECK(blocks_with_values == 2);
    // A finer cube's recorded texels resampled into it stay unrecorded.
    CctCube fine(32);
    CHECK(fine.store(up, glm::vec3(0.5f), saw));
    fine.begin_frame();
    CctCube coarse(8, nullptr, false);
    REQUIRE(raycache::resample_into(fine, coarse) == 1);
    raycache::carry_path_records(fine, coarse);
    coarse.for_each_block_state([&](const CctCube::BlockState& b) { CHECK(b.unrecorded_texels == b.valid_texels); });
    // A move this far keeps a recorded texel (the test above); here both go, as unrecorded.
    raycache::SceneChanges changes;
    changes.moved.push_back({99, {glm::vec3(20.0f, 0.0f, 0.0f), 0.5f}, {glm::vec3(20.0f, 0.5f, 0.0f), 0.5f}});
    const raycache::InvalidationCounts counts = raycache::invalidate_changes(cube, {box, -1.0f}, changes);
    CHECK(counts.dropped == 2);
    CHECK(counts.dropped_unrecorded == 2);
    CHECK(cube.valid_texels() == 0u);
}

TEST_CASE("a texel a store without a record reached in the same frame counts as unrecorded, whichever store's value it keeps") {
    // Same-frame rivals: the smaller RGB9E5 word wins (a dimmer colour here). With a recording store and a
    // plain one into one texel in one frame, in either order and with either winning, the texel's value may
    // be the plain store's, whose path nobody knows: it must count as having seen everything.
    const glm::vec3 up(0.0f, 1.0f, 0.0f);
    const glm::vec3 dim(0.1f), bright(0.9f);
    REQUIRE(raycache::CctTexel::encode(dim) < raycache::CctTexel::encode(bright));
    raycache::SceneChanges far;
    far.moved.push_back({99, {glm::vec3(20.0f, 0.0f, 0.0f), 0.5f}, {glm::vec3(20.0f, 0.5f, 0.0f), 0.5f}});
    // Invalidation may run after begin_frame() or before it (the frame's stores still pending): the same.
    for (const bool ended : {true, false}) {
        CAPTURE(ended);
        auto dropped_after = [&](auto&& stores) {
            CctCube cube(16);
            stores(cube);
            if (ended) cube.begin_frame();
            const raycache::InvalidationCounts counts = raycache::invalidate_changes(cube, {box, -1.0f}, far);
            CHECK(counts.valid_before == 1u);
            return counts.dropped_unrecorded;
        };
        CHECK(dropped_after([&](CctCube& c) { c.store(up, dim, PathRecord{}); }) == 0u); // recorded alone: kept
        CHECK(dropped_after([&](CctCube& c) { c.store(up, bright); c.store(up, dim, PathRecord{}); }) == 1u);   // recorded wins
        CHECK(dropped_after([&](CctCube& c) { c.store(up, dim); c.store(up, bright, PathRecord{}); }) == 1u);   // plain wins, first
        CHECK(dropped_after([&](CctCube& c) { c.store(up, bright, PathRecord{}); c.store(up, dim); }) == 1u);   // plain wins, second
    }
    // A later frame's recording store into an empty neighbour does not bring the rivalry back.
    CctCube cube(16);
    cube.store(up, dim, PathRecord{});
    cube.begin_frame();
    cube.store(glm::vec3(0.0f, 1.0f, 0.3f), dim, PathRecord{});
    cube.begin_frame();
    CHECK(raycache::invalidate_changes(cube, {box, -1.0f}, far).dropped == 0u);
}

TEST_CASE("paths whose hit points lie so far out that their bounds overflow are taken to meet any move") {
    // A texel looking down whose path hit (1e20, 2, 0) and (1e20, 3, 0), lit by a light at (0, 50, 0). Their
    // shadow rays pass within 1e-16 of (1000, 50, 0) on their way to the light, so a ball of radius 1
    // moving there changes them. The hit points' distance from the light squares past float's range, so
    // the cone from the light over them cannot be made: the block must go rather than be judged by NaNs
    // (which said "no meeting" and kept it).
    CctCube cube(16);
    PathRecord path;
    path.hit(3, glm::vec3(1e20f, 2.0f, 0.0f));
    path.hit(4, glm::vec3(1e20f, 3.0f, 0.0f));
    path.lit = true;
    cube.store(glm::vec3(0.0f, -1.0f, 0.0f), glm::vec3(0.5f), path);
    cube.begin_frame();
    raycache::SceneChanges across;
    across.moved.push_back({99, {glm::vec3(-1000.0f, -1000.0f, 0.0f), 1.0f}, {glm::vec3(1000.0f, 50.0f, 0.0f), 1.0f}});
    across.lights = {glm::vec3(0.0f, 50.0f, 0.0f)};
    const raycache::InvalidationCounts counts = raycache::invalidate_changes(cube, {box, -1.0f}, across);
    CHECK(counts.dropped_by_cone == 0u); // not the texel's own rays (they look down)
    CHECK(counts.dropped_by_path == 1u);
}

TEST_CASE("a moved shadow caster that no cached ray sees: the segments from the paths' hit points to the light catch its shadow") {
    // The cube stores only rays within 11 degrees of horizontal, so no texel's cone reaches the caster high
    // above ball 0; only its shadow on ball 0 changes when it moves.
    World before = make_world();
    before.balls.pop_back();
    const glm::vec3 b0 = before.balls[0].centre;
    before.balls.push_back({b0 + 0.55f * (before.light - b0), 0.4f, glm::vec3(1.0f)});
    const std::size_t caster = before.balls.size() - 1;
    World after = before;
    after.balls[caster].centre += glm::vec3(0.0f, 0.0f, 0.5f);
    // Here the oracle retraces the stored rays themselves: the path records describe the stored paths, and a
    // ray from another origin hits ball 0 elsewhere, where the CCT answers it with the stored colour anyway.
    CctCube cube(64);
    std::vector<StoredRay> rays;
    fill(cube, before, 60000, 9, 0.2f, &rays);
    auto stale = [&] {
        std::size_t n = 0;
        for (const StoredRay& r : rays)
            n += cube.load(r.texel).has_value() && before.trace(r.origin, r.direction) != after.trace(r.origin, r.direction);
        return n;
    };
    CHECK(stale() > 0);
    const raycache::InvalidationCounts counts = raycache::invalidate_changes(cube, {box, -1.0f}, move_of(before, after, caster));
    CHECK(counts.blocks_by_texel == 0); // no cone of stored rays reaches the caster
    CHECK(counts.dropped > 0);
    CHECK(stale() == 0);
}

TEST_CASE("bounces that escaped: a ball moved into a mirror's escaped reflections drops the texels it now blocks, the "
          "escape cone keeps more than treating escapes as unbounded") {
    World before = make_world();
    before.balls[2].mirror = true;
    before.balls.push_back({glm::vec3(0.0f, -40.0f, 0.0f), 0.8f, glm::vec3(1.0f, 0.2f, 0.2f)}); // far below all
    const std::size_t wanderer = before.balls.size() - 1;
    // Onto one stored path that hit the mirror alone and escaped: its hit point + 8 along its escape.
    glm::vec3 target(0.0f);
    bool found = false;
    {
        LeavingRays leaving(31);
        for (int k = 0; k < 40000 && !found; ++k) {
            const auto [n, d] = leaving.next();
            PathRecord path;
            before.trace(n, d, &path);
            if (path.objects != raycache::object_bits(2) || !path.has_escapes()) continue;
            target = path.vertex_lo + 8.0f * path.escape_lo; // one hit, one escape: the boxes are points
            found = true;
        }
    }
    REQUIRE(found);
    World after = before;
    after.balls[wanderer].centre = target;
    const raycache::SceneChanges changes = move_of(before, after, wanderer);

    // Three cubes of the same stores: records as traced, with their escapes left out (as if not recorded),
    // and with every escape recorded as unbounded (no bound on its segment).
    auto as_traced = [](PathRecord&) {};
    auto without_escapes = [](PathRecord& p) { p.escape_lo = glm::vec3(INFINITY), p.escape_hi = glm::vec3(-INFINITY); };
    auto unbounded = [](PathRecord& p) {
        if (p.has_escapes()) p.unbounded = true;
        p.escape_lo = glm::vec3(INFINITY), p.escape_hi = glm::vec3(-INFINITY);
    };
    CctCube exact(128), stripped(128), bound_less(128);
    std::vector<StoredRay> rays, rays_stripped, rays_bound_less;
    fill_edited(exact, before, 40000, 31, 1.0f, as_traced, &rays);
    fill_edited(stripped, before, 40000, 31, 1.0f, without_escapes, &rays_stripped);
    fill_edited(bound_less, before, 40000, 31, 1.0f, unbounded, &rays_bound_less);
    // The oracle retraces the stored rays (the records describe the stored paths).
    auto stale = [&](const CctCube& cube, const std::vector<StoredRay>& stored) {
        std::size_t n = 0;
        for (const StoredRay& r : stored)
            n += cube.load(r.texel).has_value() && before.trace(r.origin, r.direction) != after.trace(r.origin, r.direction);
        return n;
    };
    const std::size_t stale_before = stale(exact, rays);
    CHECK(stale_before > 0);
    const std::size_t valid = exact.valid_texels();
    raycache::invalidate_changes(exact, {box, -1.0f}, changes);
    raycache::invalidate_changes(stripped, {box, -1.0f}, changes);
    raycache::invalidate_changes(bound_less, {box, -1.0f}, changes);
    MESSAGE(valid << " texels, " << stale_before << " stored rays stale before; kept with escape cones " << exact.valid_texels()
                  << ", with escapes unbounded " << bound_less.valid_texels() << "; stale left without escape records "
                  << stale(stripped, rays_stripped));
    CHECK(stale(exact, rays) == 0);
    CHECK(stale(stripped, rays_stripped) > 0); // what the escape records catch
    CHECK(stale(bound_less, rays_bound_less) == 0);
    CHECK(exact.valid_texels() > bound_less.valid_texels());
}

TEST_CASE("a cube resampled to a coarser size keeps, per record block, the union of the records of the blocks it overlaps") {
    // Every texel of a 32-texel cube holds a record naming its own block (face, block row, block column);
    // after resample_into() and carry_path_records(), each block of the coarser cube must name exactly the
    // old blocks whose rectangles of the face overlap its own, found here by testing every pair in integers.
    CctCube from(32);
    auto key_of = [](int face, int row, int column) { return static_cast<std::uint64_t>((face * 16 + row / 2) * 16 + column / 2); };
    for (int face = 0; face < 6; ++face)
        for (int row = 0; row < 32; ++row)
            for (int column = 0; column < 32; ++column) {
                PathRecord path;
                path.hit(key_of(face, row, column), glm::vec3(5.0f));
                REQUIRE(from.store_at({face, column, row}, glm::vec3(0.5f), path));
            }
    from.begin_frame();
    for (const int size : {24, 20, 13, 7}) {
        CAPTURE(size);
        CctCube to(size);
        raycache::resample_into(from, to);
        raycache::carry_path_records(from, to);
        std::size_t blocks = 0;
        to.for_each_block_state([&](const CctCube::BlockState& t) {
            std::uint64_t expected = 0;
            from.for_each_block_state([&](const CctCube::BlockState& o) {
                const bool overlap = o.face == t.face && o.column0 * size < t.column1 * 32 && t.column0 * 32 < o.column1 * size &&
                                     o.row0 * size < t.row1 * 32 && t.row0 * 32 < o.row1 * size;
                if (overlap) expected |= raycache::object_bits(key_of(o.face, o.row0, o.column0));
            });
            CHECK(t.objects == expected);
            CHECK(t.unrecorded_texels == 0);
            ++blocks;
        });
        CHECK(blocks == static_cast<std::size_t>(6 * ((size + 1) / 2) * ((size + 1) / 2)));
    }
}

TEST_CASE("a block counts the texels that hold a value, recorded or not, on faces that end within a block") {
    // Face 20: the second tile of a row holds columns 16..19 only, so two of its blocks of each row lie on
    // the face and the rest off it. Texels are stored with and without records, some emptied
    // again; every block's count must equal the count of the texels set here that lie in it.
    CctCube cube(20);
    std::mt19937 random(7);
    std::vector<int> held(6 * 20 * 20, 0);
    auto index = [](const TexelAddress& t) { return static_cast<std::size_t>((t.face * 20 + t.row) * 20 + t.column); };
    PathRecord path;
    path.hit(3, glm::vec3(5.0f));
    for (int k = 0; k < 900; ++k) {
        const TexelAddress t{static_cast<int>(random() % 6), static_cast<int>(random() % 20), static_cast<int>(random() % 20)};
        const bool stored = random() % 2 ? cube.store_at(t, glm::vec3(0.5f), path) : cube.store_at(t, glm::vec3(0.5f));
        if (stored) held[index(t)] = 1;
    }
    cube.begin_frame();
    for (int k = 0; k < 200; ++k) {
        const TexelAddress t{static_cast<int>(random() % 6), static_cast<int>(random() % 20), static_cast<int>(random() % 20)};
        cube.invalidate(t);
        held[index(t)] = 0;
    }
    std::size_t blocks = 0, total = 0;
    cube.for_each_block_state([&](const CctCube::BlockState& b) {
        int expected = 0;
        for (int row = b.row0; row < b.row1; ++row)
            for (int column = b.column0; column < b.column1; ++column) expected += held[index({b.face, column, row})];
        CHECK(b.valid_texels == expected);
        total += static_cast<std::size_t>(b.valid_texels);
        ++blocks;
    });
    CHECK(total == cube.valid_texels());
    CHECK(blocks > 0);
}

TEST_CASE("a cube resampled to a coarser size leaves out the paths of blocks whose texels were all emptied") {
    // Two blocks of a 16-texel face that fall into one block of an 8-texel face: the first saw object 7,
    // then lost its only texel; the second holds a texel that saw object 9. The coarse block's texel came
    // from the second alone, so its record names 9 and not 7 (a union with 7 would drop it for moves of 7).
    CctCube from(16);
    PathRecord saw_7, saw_9;
    saw_7.hit(7, glm::vec3(5.0f));
    saw_9.hit(9, glm::vec3(5.0f));
    const TexelAddress emptied{RAYCACHE_FACE_POSITIVE_Z, 1, 1}, kept{RAYCACHE_FACE_POSITIVE_Z, 3, 1}; // blocks 0 and 1
    REQUIRE(from.store_at(emptied, glm::vec3(0.5f), saw_7));
    REQUIRE(from.store_at(kept, glm::vec3(0.5f), saw_9));
    from.begin_frame();
    from.invalidate(emptied);
    CctCube to(8); // texels (1,1) and (3,1) of the fine face lie in texels (0,0) and (1,0): coarse block 0
    REQUIRE(raycache::resample_into(from, to) == 1);
    raycache::carry_path_records(from, to);
    bool found = false;
    to.for_each_block_state([&](const CctCube::BlockState& b) {
        if (b.face != RAYCACHE_FACE_POSITIVE_Z || b.block != 0) return;
        found = true;
        CHECK(b.valid_texels == 1);
        CHECK(b.objects == raycache::object_bits(9));
    });
    CHECK(found);
}

TEST_CASE("a coarser cube's block that took no texel in resampling takes no path record: its first store starts it afresh") {
    // A 16-texel face resampled to 7 texels (a coarse texel spans 16 / 7 = 2.29 fine ones): the fine block
    // of columns 4 and 5 overlaps coarse blocks 0 (coarse columns 0 and 1: fine [0, 4.57)) and 1 (fine
    // [4.57, 9.14)), but its one texel, column 4 (centre 4.5), lands in coarse column 1, block 0. Block 1
    // holds nothing, so it must not take that texel's path (object 5): a texel stored there later with its
    // own path (object 6) is not a texel that saw 5, and 5's move must leave it.
    CctCube from(16);
    REQUIRE(from.store_at({RAYCACHE_FACE_POSITIVE_X, 4, 0}, glm::vec3(0.5f), saw(5)));
    from.begin_frame();
    CctCube to(7);
    REQUIRE(raycache::resample_into(from, to) == 1);
    raycache::carry_path_records(from, to);
    to.begin_frame();
    REQUIRE(to.load({RAYCACHE_FACE_POSITIVE_X, 1, 0}).has_value()); // where the resampled texel went
    REQUIRE(to.store_at({RAYCACHE_FACE_POSITIVE_X, 2, 0}, glm::vec3(0.25f), saw(6))); // coarse block 1
    to.begin_frame();
    REQUIRE((raycache::object_bits(6) & raycache::object_bits(5)) != raycache::object_bits(5));
    const raycache::InvalidationCounts counts = raycache::invalidate_changes(to, {box, -1.0f}, far_along_minus_x(5));
    CHECK(counts.dropped == 1);
    CHECK_FALSE(to.load({RAYCACHE_FACE_POSITIVE_X, 1, 0}).has_value());
    CHECK(to.load({RAYCACHE_FACE_POSITIVE_X, 2, 0}).has_value());
}

TEST_CASE("two rays stored into one texel in one frame leave the same path record whichever came first") {
    // The smaller word wins a same-frame rivalry either way; the texel's block must record both paths
    // either way too, or which texels a move drops (and so later frames) would depend on thread timing.
    const glm::vec3 dim(0.1f), bright(0.9f); // dim packs to the smaller word
    REQUIRE(raycache::CctTexel::encode(dim) < raycache::CctTexel::encode(bright));
    const PathRecord saw_5 = saw(5), saw_6 = saw(6);
    const TexelAddress t{RAYCACHE_FACE_POSITIVE_X, 3, 4};
    auto objects_after = [&](const glm::vec3& first, const PathRecord& first_path, const glm::vec3& second, const PathRecord& second_path) {
        CctCube cube(16);
        cube.store_at(t, first, first_path);
        cube.store_at(t, second, second_path);
        cube.begin_frame();
        CHECK(*cube.load(t) == raycache::CctTexel::decode(raycache::CctTexel::encode(dim))); // the smaller word won
        std::uint64_t objects = 0;
        cube.for_each_block_state([&](const CctCube::BlockState& b) { objects |= b.objects; });
        return objects;
    };
    const std::uint64_t both = raycache::object_bits(5) | raycache::object_bits(6);
    CHECK(objects_after(dim, saw_5, bright, saw_6) == both);   // the larger word came second and lost
    CHECK(objects_after(bright, saw_6, dim, saw_5) == both);   // the larger word came first and was replaced
}

TEST_CASE("an invalidation pass has a run for every 16 allocated tiles and refuses a run it does not have") {
    // Face +X of a 64-texel cube holds 16 tiles; face -X one more: 17 tiles, so 2 runs. Nothing moved that
    // its rays can reach, so the passes keep every texel, and run(2) is refused before touching anything.
    CctCube cube(64);
    for (int row = 0; row < 64; row += 16)
        for (int column = 0; column < 64; column += 16) REQUIRE(cube.store_at({RAYCACHE_FACE_POSITIVE_X, column, row}, glm::vec3(0.5f), saw(6)));
    REQUIRE(cube.store_at({RAYCACHE_FACE_NEGATIVE_X, 0, 0}, glm::vec3(0.5f), saw(6)));
    cube.begin_frame();
    REQUIRE(cube.allocated_tiles() == 17u);
    const raycache::SceneChanges changes = far_along_minus_x(5);
    const std::unique_ptr<raycache::InvalidationPass> pass = raycache::make_invalidation_pass(cube, {box, -1.0f}, changes);
    CHECK(pass->runs() == 2u);
    CHECK_THROWS_AS(pass->run(2), std::out_of_range);
    pass->run(1);
    pass->run(0);
    const raycache::InvalidationCounts counts = pass->finish();
    CHECK(counts.valid_before == 17u);
    CHECK(counts.dropped == 0u);
    CHECK(cube.valid_texels() == 17u);
}

TEST_CASE("changes with a sphere or light that is not finite, or a negative radius, are refused before any texel goes") {
    const World before = make_world();
    CctCube cube(32);
    fill(cube, before, 30000, 3);
    const std::size_t valid = cube.valid_texels();
    REQUIRE(valid > 4000);
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    // A move that would drop texels if it were taken as given: a ball swept through the cube's surroundings.
    raycache::SceneChanges good;
    good.moved.push_back({7u, {glm::vec3(0.0f, 0.0f, 3.0f), 0.5f}, {glm::vec3(0.0f, 0.0f, 2.0f), 0.5f}});
    auto bad = [&](auto&& edit) {
        raycache::SceneChanges c = good;
        edit(c);
        return c;
    };
    const raycache::SceneChanges refused[] = {
        bad([&](raycache::SceneChanges& c) { c.moved[0].after.centre.y = nan; }),
        bad([&](raycache::SceneChanges& c) { c.moved[0].before.centre.x = inf; }),
        bad([&](raycache::SceneChanges& c) { c.moved[0].after.radius = nan; }),
        bad([&](raycache::SceneChanges& c) { c.moved[0].before.radius = -0.5f; }),
        bad([&](raycache::SceneChanges& c) { c.moved[0].after.radius = inf; }),
        bad([&](raycache::SceneChanges& c) { c.lights = {glm::vec3(0.0f, nan, 0.0f)}; }),
    };
    for (const raycache::SceneChanges& c : refused) {
        CHECK_THROWS_AS(raycache::invalidate_changes(cube, {box, -1.0f}, c), std::invalid_argument);
        CHECK(cube.valid_texels() == valid);
    }
    // A radius of 0 (a point) is a sphere; the good change itself goes through and drops something.
    CHECK_NOTHROW(raycache::invalidate_changes(cube, {box, -1.0f}, bad([](raycache::SceneChanges& c) { c.moved[0].after.radius = 0.0f; })));
    CHECK(cube.valid_texels() < valid);
}
