// The Embree tracer on a dynamic scene (dynamic-N) with CCT and CDCT caches: the tracer moves the objects
// (its BVH follows them), and SceneCache::scene_changed() drops what moved objects can have changed. An
// oracle (stale_oracle.hpp) retraces, after each move, every texel still valid, with the cache off in the
// scene before and after the move; a texel is stale when some ray's colour changed by more than 1e-4 in a
// channel (CDCT: see stale_oracle.hpp). `exact` must leave none, `none` must leave some. A cache saved and
// loaded back invalidates as the one it was saved from.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <string>

#include <unistd.h>

#include "rcx/image.hpp"
#include "rcx/scene.hpp"
#include "stale_oracle.hpp"
#include "tracer.hpp"

namespace {

using raycache::embree::Invalidation;
using raycache::embree::SceneCache;

bool wuson_missing() { return !std::filesystem::exists(rcx::SceneParams{}.mesh_path); }

struct Run {
    std::size_t stale = 0, checked = 0;
    double kept = 0.0;
};

// Renders `frames` frames of `scene` (fixed camera, objects moving) with CCT or CDCT caches on 32-texel
// faces, invalidating with `policy` after each move, and runs the oracle after each move.
// Caches as the Embree tracer makes them: crossings over 0.5 behind a surface miss (so a CDCT texel's rays
// end there, and farther moves keep it).
SceneCache tracer_caches(raycache::embree::Technique technique) {
    raycache::embree::SceneCacheSettings settings;
    settings.relief.max_gap = 0.5f;
    settings.path_records = raycache::embree::PathRecords::always; // as the tracer's for dynamic scenes
    return SceneCache(technique, settings);
}

// 96 x 96 frames on two threads through `caches`.
rcx::embree::RenderSettings settings_for(SceneCache& caches) {
    rcx::embree::RenderSettings s;
    s.width = s.height = 96;
    s.mode = caches.technique() == raycache::embree::Technique::cdct ? rcx::CacheMode::cdct : rcx::CacheMode::cct;
    s.caches = &caches;
    s.threads = 2;
    return s;
}

Run run(const rcx::Scene& scene, Invalidation policy, int frames, raycache::embree::Technique technique = raycache::embree::Technique::cct) {
    const bool cdct = technique == raycache::embree::Technique::cdct;
    rcx::embree::Tracer tracer(scene);
    SceneCache caches = tracer_caches(technique);
    tracer.attach_caches(caches, 32);
    const rcx::embree::RenderSettings s = settings_for(caches);
    Run r;
    double kept_sum = 0.0;
    for (int f = 0; f < frames; ++f) {
        if (f > 0) {
            const rcx::embree::Tracer before(scene.at_frame(f - 1));
            const raycache::embree::SceneChange change = tracer.move_to(scene.at_frame(f));
            REQUIRE(!change.moved.empty());
            kept_sum += caches.scene_changed(change, policy).kept_fraction();
            const rcx::embree::StaleCount c =
                cdct ? rcx::embree::stale_cdct_texels(caches, before, tracer) : rcx::embree::stale_cct_texels(caches, before, tracer);
            r.stale += c.stale;
            r.checked += c.checked;
        }
        tracer.render(scene.camera_at(0), s);
        caches.begin_frame();
    }
    r.kept = kept_sum / (frames - 1);
    return r;
}

} // namespace

TEST_CASE("dynamic-N: the tracer's BVH follows the moved objects (a moved frame equals a tracer built at that frame)") {
    if (wuson_missing()) return;
    const rcx::Scene scene = rcx::make_scene("dynamic-4");
    rcx::embree::Tracer moved(scene);
    moved.move_to(scene.at_frame(7));
    const rcx::embree::Tracer built(scene.at_frame(7));
    rcx::embree::RenderSettings s;
    s.width = s.height = 64;
    const rcx::Image a = moved.render(scene.camera_at(0), s), b = built.render(scene.camera_at(0), s);
    CHECK(!std::isfinite(rcx::compare(a, b).psnr_db));
    const rcx::Image still = rcx::embree::Tracer(scene).render(scene.camera_at(0), s);
    CHECK(std::isfinite(rcx::compare(a, still).psnr_db)); // and the objects did move
}

TEST_CASE("dynamic-N with CCT caches: after each move the oracle finds no stale texel under exact, and finds some under none") {
    if (wuson_missing()) return;
    rcx::Scene scene = rcx::make_scene("dynamic-8");
    const Run none = run(scene, Invalidation::none, 4);
    const Run exact = run(scene, Invalidation::exact, 4);
    MESSAGE("none: " << none.stale << " stale of " << none.checked << " texels checked; exact: " << exact.stale << " stale of "
                     << exact.checked << ", kept " << 100.0 * exact.kept << "% a move");
    CHECK(none.stale > 0);
    CHECK(exact.checked > 1000);
    CHECK(exact.stale == 0);

    // One object moving (the others still): exact keeps most texels, and none of them is stale.
    rcx::Scene one = scene;
    one.motions.resize(1);
    const Run single = run(one, Invalidation::exact, 4);
    MESSAGE("one moving object: " << single.stale << " stale of " << single.checked << ", kept " << 100.0 * single.kept << "% a move");
    CHECK(single.stale == 0);
    CHECK(single.kept > 0.5);
}

TEST_CASE("dynamic-N with CDCT caches: after each move the oracle finds no stale texel under exact, and finds some under none") {
    if (wuson_missing()) return;
    rcx::Scene scene = rcx::make_scene("dynamic-8");
    const auto cdct = raycache::embree::Technique::cdct;
    const Run none = run(scene, Invalidation::none, 4, cdct);
    const Run exact = run(scene, Invalidation::exact, 4, cdct);
    MESSAGE("none: " << none.stale << " stale of " << none.checked << " texels checked; exact: " << exact.stale << " stale of "
                     << exact.checked << ", kept " << 100.0 * exact.kept << "% a move");
    CHECK(none.stale > 0);
    CHECK(exact.checked > 500); // exact keeps 40% a move with 8 movers, of fewer texels than the CCT fills
    CHECK(exact.stale == 0);

    rcx::Scene one = scene;
    one.motions.resize(1);
    const Run single = run(one, Invalidation::exact, 4, cdct);
    MESSAGE("one moving object: " << single.stale << " stale of " << single.checked << ", kept " << 100.0 * single.kept << "% a move");
    CHECK(single.stale == 0);
    CHECK(single.kept > 0.5);
}

TEST_CASE("dynamic-N: caches saved after some moves and loaded back lose exactly what the saved ones lose at the next move") {
    // A cache file keeps every block's path record and how far out each cube answers rays, so a loaded cache
    // keeps and drops the same texels under exact invalidation as the cache it was saved from.
    if (wuson_missing()) return;
    const rcx::Scene scene = rcx::make_scene("dynamic-8");
    for (const auto technique : {raycache::embree::Technique::cct, raycache::embree::Technique::cdct}) {
        const bool cdct = technique == raycache::embree::Technique::cdct;
        CAPTURE(cdct);
        rcx::embree::Tracer tracer(scene);
        SceneCache caches = tracer_caches(technique);
        tracer.attach_caches(caches, 32);
        const rcx::embree::RenderSettings s = settings_for(caches);
        for (int f = 0; f < 3; ++f) {
            if (f > 0) caches.scene_changed(tracer.move_to(scene.at_frame(f)), Invalidation::exact);
            tracer.render(scene.camera_at(0), s);
            caches.begin_frame();
        }
        const std::string path = (std::filesystem::temp_directory_path() /
                                  ("raycache-dynamic-" + std::to_string(::getpid()) + "-" + std::to_string(cdct) + ".rcc")).string();
        const raycache::SceneIdentity identity{8, "dynamic-8"};
        caches.save(path, identity);
        SceneCache loaded = tracer_caches(technique);
        // Where the saved cubes sit now (moved cubes follow their objects by the spheres' offsets, which
        // bounds_of() of the moved geometry can round otherwise): a load needs the same placements.
        for (const raycache::embree::ObjectId id : caches.objects()) loaded.attach(id, 32, *caches.object_bounds(id));
        loaded.load(path, identity);
        std::filesystem::remove(path);
        const raycache::embree::SceneChange change = tracer.move_to(scene.at_frame(3));
        const auto original = caches.scene_changed(change, Invalidation::exact);
        const auto reloaded = loaded.scene_changed(change, Invalidation::exact);
        MESSAGE(std::string(cdct ? "CDCT" : "CCT") << ": " << original.valid_before << " texels, the saved cache keeps " << 100.0 * original.kept_fraction()
                                        << "%, the loaded one " << 100.0 * reloaded.kept_fraction() << "%");
        CHECK(original.valid_before > 500u);
        CHECK(reloaded.valid_before == original.valid_before);
        CHECK(reloaded.dropped == original.dropped);
        CHECK(reloaded.dropped_unrecorded == 0u);
        CHECK(original.kept_fraction() > 0.3);
    }
}
