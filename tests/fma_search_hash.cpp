// fma_search_hash: the CDCT searches give the same bits whether or not the compiler fuses a * b + c into
// an FMA. Built twice (tests/CMakeLists.txt): plainly, and with -mfma -ffp-contract=fast. A CTest test runs
//   plain --write-inputs in.bin       cubes (analytic words, and the rays that fill the stored ones) and
//                                     search rays, generated once, so both builds search the same inputs
//   plain --run in.bin plain.dump     each build: fills the stored cubes through cdct_cached_trace, then
//   fma   --run in.bin fma.dump       runs every search below and writes each result and a hash
//   plain --compare plain.dump fma.dump   the results must be equal bit for bit (hit, distance, colour,
//                                     point, texels read; the stored cubes' words), and the FMA build
//                                     must really fuse (else the test proves nothing)
// Searches: secant_search over rcx_test::secant_parameter_sets() (8 sets), relief_search linear and over a
// depth pyramid (4 sets each), on 6,000 rays through 6 cubes (analytic, and filled by stores with holes):
// 48,000 secant and 48,000 relief calls.
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <raycache/raycache.hpp>

#include "cdct_scenes.hpp"

using namespace raycache;

namespace {

// ---- a little binary file format: raw little-endian values, vectors as count then elements ----------

struct Writer {
    std::FILE* f;
    explicit Writer(const std::string& path) : f(std::fopen(path.c_str(), "wb")) {
        if (!f) throw std::runtime_error("cannot write " + path);
    }
    ~Writer() { std::fclose(f); }
    template <class T> void put(const T& value) { std::fwrite(&value, sizeof(T), 1, f); }
    template <class T> void put_vector(const std::vector<T>& values) {
        put(static_cast<std::uint64_t>(values.size()));
        if (!values.empty()) std::fwrite(values.data(), sizeof(T), values.size(), f);
    }
};

struct Reader {
    std::FILE* f;
    explicit Reader(const std::string& path) : f(std::fopen(path.c_str(), "rb")) {
        if (!f) throw std::runtime_error("cannot read " + path);
    }
    ~Reader() { std::fclose(f); }
    template <class T> T get() {
        T value;
        if (std::fread(&value, sizeof(T), 1, f) != 1) throw std::runtime_error("truncated file");
        return value;
    }
    template <class T> std::vector<T> get_vector() {
        std::vector<T> values(get<std::uint64_t>());
        if (!values.empty() && std::fread(values.data(), sizeof(T), values.size(), f) != values.size())
            throw std::runtime_error("truncated file");
        return values;
    }
};

// ---- inputs ------------------------------------------------------------------------------------------

struct CubeShape {
    std::int32_t face_size;
    float centre[3];
    float half_size;
};

std::vector<CubeShape> shapes_of(const rcx_test::CdctScene& s) {
    std::vector<CubeShape> shapes;
    for (std::size_t c = 0; c < s.cubes.size(); ++c)
        shapes.push_back({s.cubes[c].face_size(), {s.bounds[c].centre.x, s.bounds[c].centre.y, s.bounds[c].centre.z},
                          s.bounds[c].half_size});
    return shapes;
}

rcx_test::CdctScene scene_of(const std::vector<CubeShape>& shapes) {
    rcx_test::CdctScene s;
    for (const CubeShape& c : shapes)
        s.add(c.face_size, CubeBounds{glm::vec3(c.centre[0], c.centre[1], c.centre[2]), c.half_size});
    return s;
}

void write_inputs(const std::string& path) {
    std::mt19937 rng(2024);
    const rcx_test::CdctScene analytic = rcx_test::make_analytic_scene(rng, true);
    const std::vector<rcx_test::CdctRay> analytic_rays = rcx_test::search_rays(analytic, rng, 1000);
    std::vector<rcx_test::TracedSample> samples;
    const rcx_test::CdctScene stored = rcx_test::make_stored_scene(rng, 2500, 3, samples);
    const std::vector<rcx_test::CdctRay> stored_rays = rcx_test::search_rays(stored, rng, 1000);
    Writer w(path);
    w.put_vector(shapes_of(analytic));
    w.put_vector(analytic.words());
    w.put_vector(analytic_rays);
    w.put_vector(shapes_of(stored));
    w.put_vector(samples);
    w.put_vector(stored_rays);
}

// ---- running the searches ------------------------------------------------------------------------------

// One search's answer, every bit of it.
struct Record {
    std::uint32_t hit;
    std::int32_t texels_read;
    float distance;
    float color[3];
    float point[3];
};

Record record_of(const ReliefResult& r) {
    return Record{r.hit ? 1u : 0u,
                  r.texels_read,
                  r.distance,
                  {r.color.x, r.color.y, r.color.z},
                  {r.point.x, r.point.y, r.point.z}};
}

std::uint64_t fnv1a(const void* data, std::size_t bytes) {
    std::uint64_t h = 14695981039346656037ull;
    const unsigned char* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 1099511628211ull;
    return h;
}

// Whether this build fuses a * b + c: 1 + 2^-12 squared is 1 + 2^-11 + 2^-24, which rounds to 1 + 2^-11;
// only a fused multiply-add keeps the 2^-24.
bool build_fuses() {
    volatile float a = 1.0f + 0x1p-12f, c = -(1.0f + 0x1p-11f);
    const float x = a, z = c;
    return x * x + z != 0.0f;
}

struct Kind {
    std::string name;
    std::vector<Record> records;
};

std::vector<ReliefParameters> relief_parameter_sets() {
    const float inf = std::numeric_limits<float>::infinity();
    return {{2.0f, 0.2f, 1024, 100.0f, inf, DepthSearch::relief},
            {0.2f, 0.02f, 1024, 100.0f, inf, DepthSearch::relief},
            {0.05f, 0.002f, 300, 100.0f, inf, DepthSearch::relief},
            {0.2f, 0.02f, 1024, 100.0f, 0.3f, DepthSearch::relief}};
}

int run(const std::string& in, const std::string& out) {
    Reader r(in);
    rcx_test::CdctScene scenes[2] = {scene_of(r.get_vector<CubeShape>()), {}};
    const std::vector<std::uint64_t> words = r.get_vector<std::uint64_t>();
    const std::vector<rcx_test::CdctRay> analytic_rays = r.get_vector<rcx_test::CdctRay>();
    scenes[1] = scene_of(r.get_vector<CubeShape>());
    const std::vector<rcx_test::TracedSample> samples = r.get_vector<rcx_test::TracedSample>();
    const std::vector<rcx_test::CdctRay> stored_rays = r.get_vector<rcx_test::CdctRay>();
    const std::vector<rcx_test::CdctRay>* rays[2] = {&analytic_rays, &stored_rays};

    for (std::size_t c = 0; c < scenes[0].cubes.size(); ++c) {
        rcx_test::store_words(scenes[0].cubes[c], words.data() + scenes[0].descriptors[c].first_texel);
        scenes[0].cubes[c].begin_frame();
    }
    // The stored cubes, filled through cdct_cached_trace by this build (its searches and stores).
    rcx_test::apply_samples(scenes[1], samples, ReliefParameters{});

    std::vector<Kind> kinds;
    Kind stores{"stored cube words", {}};
    for (const std::uint64_t w : scenes[1].words()) { // hit: valid; distance and colour[0]: the word's halves
        Record rec{CdctTexel::is_valid(w) ? 1u : 0u, 0, 0.0f, {}, {}};
        const std::uint32_t color_bits = static_cast<std::uint32_t>(w), distance_bits = static_cast<std::uint32_t>(w >> 32);
        std::memcpy(&rec.distance, &distance_bits, 4);
        std::memcpy(&rec.color[0], &color_bits, 4);
        stores.records.push_back(rec);
    }
    kinds.push_back(stores);

    const char* scene_names[2] = {"analytic cubes", "stored cubes"};
    for (int k = 0; k < 2; ++k) {
        rcx_test::CdctScene& s = scenes[k];
        std::vector<std::unique_ptr<DepthPyramid>> pyramids;
        for (const CdctCube& cube : s.cubes) {
            pyramids.push_back(std::make_unique<DepthPyramid>(cube.face_size()));
            pyramids.back()->rebuild(cube);
        }
        Kind secant{std::string("secant_search, ") + scene_names[k], {}};
        Kind relief{std::string("relief_search, ") + scene_names[k], {}};
        Kind pyramid{std::string("relief_search over a pyramid, ") + scene_names[k], {}};
        for (const ReliefParameters& p : rcx_test::secant_parameter_sets())
            for (const rcx_test::CdctRay& q : *rays[k])
                secant.records.push_back(record_of(secant_search(s.cubes[q.cube], s.bounds[q.cube], q.origin, q.direction, p)));
        for (const ReliefParameters& p : relief_parameter_sets())
            for (const rcx_test::CdctRay& q : *rays[k]) {
                relief.records.push_back(record_of(relief_search(s.cubes[q.cube], s.bounds[q.cube], q.origin, q.direction, p)));
                pyramid.records.push_back(record_of(
                    relief_search(s.cubes[q.cube], s.bounds[q.cube], q.origin, q.direction, p, pyramids[q.cube].get())));
            }
        kinds.push_back(secant);
        kinds.push_back(relief);
        kinds.push_back(pyramid);
    }

    const bool fuses = build_fuses();
    std::printf("this build %s a * b + c into an FMA\n", fuses ? "fuses" : "does not fuse");
    Writer w(out);
    w.put(static_cast<std::uint32_t>(fuses));
    w.put(static_cast<std::uint32_t>(kinds.size()));
    for (const Kind& kind : kinds) {
        std::size_t hits = 0;
        long long texels = 0;
        for (const Record& rec : kind.records) hits += rec.hit, texels += rec.texels_read;
        std::printf("%-45s %6zu results, %6zu hits, %8lld texels read, FNV-1a %016llx\n", kind.name.c_str(),
                    kind.records.size(), hits, texels,
                    static_cast<unsigned long long>(fnv1a(kind.records.data(), kind.records.size() * sizeof(Record))));
        w.put_vector(std::vector<char>(kind.name.begin(), kind.name.end()));
        w.put_vector(kind.records);
    }
    return 0;
}

// ---- comparing two builds' results ---------------------------------------------------------------------

struct Dump {
    bool fuses = false;
    std::vector<Kind> kinds;
};

Dump read_dump(const std::string& path) {
    Reader r(path);
    Dump d;
    d.fuses = r.get<std::uint32_t>() != 0;
    const std::uint32_t n = r.get<std::uint32_t>();
    for (std::uint32_t k = 0; k < n; ++k) {
        const std::vector<char> name = r.get_vector<char>();
        d.kinds.push_back(Kind{std::string(name.begin(), name.end()), r.get_vector<Record>()});
    }
    return d;
}

int compare(const std::string& plain_path, const std::string& fma_path) {
    const Dump plain = read_dump(plain_path), fma = read_dump(fma_path);
    int failures = 0;
    if (plain.fuses || !fma.fuses) {
        std::printf("FAIL: the plain build must not fuse a * b + c and the FMA build must (plain %s, FMA %s)\n",
                    plain.fuses ? "fuses" : "does not", fma.fuses ? "fuses" : "does not");
        ++failures;
    }
    if (plain.kinds.size() != fma.kinds.size()) {
        std::printf("FAIL: the dumps hold different searches\n");
        return 1;
    }
    for (std::size_t k = 0; k < plain.kinds.size(); ++k) {
        const std::vector<Record>& a = plain.kinds[k].records;
        const std::vector<Record>& b = fma.kinds[k].records;
        if (a.size() != b.size()) {
            std::printf("FAIL %s: %zu results against %zu\n", plain.kinds[k].name.c_str(), a.size(), b.size());
            ++failures;
            continue;
        }
        std::size_t differ = 0, distance_differs = 0;
        for (std::size_t i = 0; i < a.size(); ++i) {
            if (std::memcmp(&a[i], &b[i], sizeof(Record)) == 0) continue;
            distance_differs += std::memcmp(&a[i].distance, &b[i].distance, sizeof(float)) != 0;
            if (differ++ < 5)
                std::printf("  %s #%zu: plain hit %u read %d t %a colour (%a, %a, %a) point (%a, %a, %a); FMA hit %u "
                            "read %d t %a colour (%a, %a, %a) point (%a, %a, %a)\n",
                            plain.kinds[k].name.c_str(), i, a[i].hit, a[i].texels_read, a[i].distance, a[i].color[0],
                            a[i].color[1], a[i].color[2], a[i].point[0], a[i].point[1], a[i].point[2], b[i].hit,
                            b[i].texels_read, b[i].distance, b[i].color[0], b[i].color[1], b[i].color[2], b[i].point[0],
                            b[i].point[1], b[i].point[2]);
        }
        const std::uint64_t ha = fnv1a(a.data(), a.size() * sizeof(Record)), hb = fnv1a(b.data(), b.size() * sizeof(Record));
        std::printf("%s %-45s %zu results, %zu differ (%zu in distance); FNV-1a plain %016llx, FMA %016llx\n",
                    differ == 0 && ha == hb ? "ok  " : "FAIL", plain.kinds[k].name.c_str(), a.size(), differ,
                    distance_differs, static_cast<unsigned long long>(ha), static_cast<unsigned long long>(hb));
        failures += differ != 0 || ha != hb;
    }
    return failures == 0 ? 0 : 1;
}

} // namespace

int main(int argc, char** argv) {
    try {
        const std::string mode = argc > 1 ? argv[1] : "";
        if (mode == "--write-inputs" && argc == 3) {
            write_inputs(argv[2]);
            return 0;
        }
        if (mode == "--run" && argc == 4) return run(argv[2], argv[3]);
        if (mode == "--compare" && argc == 4) return compare(argv[2], argv[3]);
        std::fprintf(stderr, "usage: %s --write-inputs IN | --run IN DUMP | --compare PLAIN_DUMP FMA_DUMP\n", argv[0]);
        return 2;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s\n", e.what());
        return 1;
    }
}
