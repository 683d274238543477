// The ray-space hierarchy engine; see rsh_engine.hpp.
#include "rsh_engine.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <raycache/shared/rsh_layout.h>

namespace rcx::gpu {

namespace {

// The push constants of every rsh_*.comp (shaders/rsh_common.glsl).
struct Push {
    std::uint32_t capacity = 0, off1 = 0, off2 = 0, off3 = 0;
    std::uint32_t parent_first = 0, child_first = 0, count = 0, arg = 0;
};
static_assert(sizeof(Push) == 32, "rsh push constants");

// Control words and argument slots (shaders/rsh_common.glsl).
constexpr std::uint32_t ctl_rays = 3, ctl_args = 8, ctl_build_args = 64, ctl_words = 256;
constexpr std::uint32_t acc_tests = 32, acc_leaf_pairs = 34, acc_live = 38, acc_slots = 39;
constexpr std::uint32_t acc_traces = 128, acc_trace_count = 64; // per trace of a recording: overflows, largest stream wanted
enum Arg : std::uint32_t { arg_traverse, arg_scan0, arg_scan1, arg_scan2, arg_add1, arg_add0, arg_scatter, arg_final };
constexpr std::uint32_t plan_final = 0x10000u, plan_first = 0x20000u, plan_prefix_sum = 0x40000u, plan_build = 0x80000u;
constexpr std::uint32_t scan_block = 1024;

// Offsets of the scan levels 1, 2 and 3 (the total) in a scan buffer over at most n elements.
struct ScanLayout {
    std::uint32_t off1, off2, off3;
};
ScanLayout scan_layout(std::uint64_t n) {
    const std::uint64_t g0 = (n + scan_block - 1) / scan_block, g1 = (g0 + scan_block - 1) / scan_block;
    return {static_cast<std::uint32_t>(n), static_cast<std::uint32_t>(n + g0), static_cast<std::uint32_t>(n + g0 + g1)};
}

enum Phase { phase_none = -1, phase_build, phase_traverse, phase_compaction, phase_final, phase_count };

double ms_since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

} // namespace

struct RshEngine::Impl {
    vk::Context& context;
    RshSettings settings;
    std::unique_ptr<vk::ComputePipeline> prepare, build, root, plan, traverse, scan, scan_add, scatter, final_pass;
    std::unique_ptr<vk::Buffer> control, spheres, nodes, pairs[2], flags, scan_words, count_word;
    std::uint32_t off1 = 0, off2 = 0, off3 = 0;
    std::uint32_t batch = 0;
    std::unique_ptr<vk::Timestamps> timestamps; // with settings.timestamps
    // The recording since begin(): batches and levels recorded, buffers it uses that were replaced since.
    bool recording = false;
    std::uint32_t recorded_batches = 0, recorded_levels = 0, recorded_traces = 0;
    // The batch size of each trace of a recording, by its index (a frame records the same sequence of
    // traces every time): lowered where that trace overflowed, so that traces of few rays keep big batches.
    std::vector<std::uint32_t> trace_batch, trace_primitives; // ... and its primitives in the last recording
    std::vector<std::unique_ptr<vk::Buffer>> retired;
    bool marks_full = false;
    const vk::Buffer* spheres_of = nullptr; // whose bounding spheres `spheres` holds in this recording
    std::uint32_t spheres_count = 0;

    // Grows `buffer` to `bytes`; a replaced buffer stays alive until end() (a recorded command may use it).
    void grow(std::unique_ptr<vk::Buffer>& buffer, std::uint64_t bytes) {
        if (buffer && buffer->size() >= bytes) return;
        if (buffer) retired.push_back(std::move(buffer));
        buffer = std::make_unique<vk::Buffer>(context, std::max<std::uint64_t>(bytes, 16));
    }

    // Timestamps of one submission: the interval before each mark belongs to the mark's phase.
    std::vector<int> marks;
    void mark(vk::Commands& c, int phase) {
        if (!timestamps || !timestamps->available()) return;
        if (marks.size() >= timestamps->count()) {
            marks_full = true;
            return;
        }
        timestamps->write(c, static_cast<std::uint32_t>(marks.size()));
        marks.push_back(phase);
    }
    void begin_marks(vk::Commands& c) {
        marks.clear();
        marks_full = false;
        if (!timestamps) return;
        timestamps->reset(c);
        mark(c, -1);
    }
    void collect(RshStats& s) {
        if (!timestamps || marks.size() < 2) return;
        const std::vector<std::uint64_t> t = timestamps->ticks(static_cast<std::uint32_t>(marks.size()));
        if (t.size() != marks.size()) return;
        double* ms[phase_count] = {&s.build_ms, &s.traverse_ms, &s.compaction_ms, &s.final_ms};
        for (std::size_t i = 1; i < marks.size(); ++i)
            if (marks[i] >= 0) *ms[marks[i]] += timestamps->milliseconds(t[i - 1], t[i]);
        s.timed = !marks_full; // more passes than timestamps: the phases are partial
    }

    Impl(vk::Context& c, const RshSettings& s) : context(c), settings(s) {}
};

RshEngine::RshEngine(vk::Context& context, const std::string& spirv_dir, const RshSettings& settings)
    : impl_(std::make_unique<Impl>(context, settings)) {
    Impl& e = *impl_;
    if (!context.int64_atomics())
        throw std::invalid_argument("ray-space hierarchy: the device needs shaderInt64 and shaderBufferInt64Atomics");
    if (settings.pair_capacity < 64 || settings.pair_capacity > (1u << 24))
        throw std::invalid_argument("ray-space hierarchy: the pair capacity must be 64 .. 2^24");
    const std::vector<VkDescriptorType> bindings(10, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER);
    auto load = [&](const char* name) {
        return std::make_unique<vk::ComputePipeline>(context, spirv_dir + "/" + name + ".spv", bindings, sizeof(Push));
    };
    e.prepare = load("rsh_prepare");
    e.build = load("rsh_build");
    e.root = load("rsh_root");
    e.plan = load("rsh_plan");
    e.traverse = load("rsh_traverse");
    e.scan = load("rsh_scan");
    e.scan_add = load("rsh_scan_add");
    e.scatter = load("rsh_scatter");
    e.final_pass = load("rsh_final");

    const std::uint64_t c = settings.pair_capacity;
    const std::uint64_t n0 = 4 * c;
    const ScanLayout scan = scan_layout(n0);
    e.off1 = scan.off1, e.off2 = scan.off2, e.off3 = scan.off3;
    e.control = std::make_unique<vk::Buffer>(context, ctl_words * 4);
    e.control->fill(0u);
    e.pairs[0] = std::make_unique<vk::Buffer>(context, c * 8);
    e.pairs[1] = std::make_unique<vk::Buffer>(context, c * 8);
    e.flags = std::make_unique<vk::Buffer>(context, n0 * 4);
    e.scan_words = std::make_unique<vk::Buffer>(context, (static_cast<std::uint64_t>(e.off3) + 4) * 4);
    e.batch = settings.pair_capacity;

    if (settings.timestamps) e.timestamps = std::make_unique<vk::Timestamps>(context, 8192);
}

RshEngine::~RshEngine() = default;

std::uint32_t RshEngine::batch_size() const noexcept { return impl_->batch; }
std::uint32_t RshEngine::pair_capacity() const noexcept { return impl_->settings.pair_capacity; }

std::uint64_t RshEngine::prefix_sum_bytes(std::uint32_t max_elements) noexcept {
    return (std::uint64_t{scan_layout(max_elements).off3} + 4) * 4;
}
std::uint32_t RshEngine::prefix_sum_total_word(std::uint32_t max_elements) noexcept { return scan_layout(max_elements).off3; }

void RshEngine::begin(vk::Commands& c) {
    Impl& e = *impl_;
    e.recording = true; // a recording whose submission failed is simply dropped
    e.retired.clear();
    e.spheres_of = nullptr, e.spheres_count = 0;
    e.recorded_batches = e.recorded_levels = e.recorded_traces = 0;
    e.begin_marks(c);
    c.fill(*e.control, 0u);
    c.barrier();
}

RshStats RshEngine::end() {
    Impl& e = *impl_;
    if (!e.recording) throw std::logic_error("ray-space hierarchy: end() without begin()");
    e.recording = false;
    e.retired.clear();
    RshStats s;
    e.collect(s);
    const std::uint32_t* ctl = e.control->as<std::uint32_t>();
    auto word64 = [&](std::uint32_t at) { return std::uint64_t{ctl[at]} | (std::uint64_t{ctl[at + 1]} << 32); };
    s.rays = ctl[acc_slots];
    s.live_rays = ctl[acc_live];
    s.levels = e.recorded_levels;
    s.cone_sphere_tests = word64(acc_tests);
    s.leaf_pairs = word64(acc_leaf_pairs);
    for (std::uint32_t k = 0; k < std::min(e.recorded_traces, acc_trace_count); ++k) {
        const std::uint32_t overflows = ctl[acc_traces + 2 * k];
        if (overflows == 0) continue;
        s.overflows += overflows;
        // Section 3.4: more, smaller batches for this trace. The streams grow about in proportion to the
        // batch: aim 20% below the capacity by the factor the largest stream (estimated across the cut
        // levels) exceeded it, and at least halve, so that one more recording usually fits.
        std::uint32_t& batch = e.trace_batch[k];
        batch = std::min(batch, e.trace_primitives[k]); // what the batches held
        if (batch <= 1)
            throw std::runtime_error("ray-space hierarchy: one primitive meets more leaves than the pair capacity (" +
                                     std::to_string(e.settings.pair_capacity) + "); raise it");
        const double wanted = std::max<double>(ctl[acc_traces + 2 * k + 1], e.settings.pair_capacity);
        const double scaled = 0.8 * batch * (e.settings.pair_capacity / wanted);
        batch = static_cast<std::uint32_t>(std::max(1.0, std::min<double>(batch / 2, scaled)));
        e.batch = std::min(e.batch, batch);
    }
    s.batches = e.recorded_batches - s.overflows;
    return s;
}

void RshEngine::record_prefix_sum(vk::Commands& c, const vk::Buffer& flags, const vk::Buffer& counts,
                                  std::uint32_t count_word, std::uint32_t scale, std::uint32_t max_elements,
                                  const vk::Buffer& sums) {
    Impl& e = *impl_;
    if (!e.recording) throw std::logic_error("ray-space hierarchy: record_prefix_sum() outside begin() .. end()");
    if (max_elements >= (1u << 30) || sums.size() < prefix_sum_bytes(max_elements) ||
        flags.size() < std::uint64_t{max_elements} * 4 || counts.size() < (std::uint64_t{count_word} + 1) * 4)
        throw std::invalid_argument("ray-space hierarchy: record_prefix_sum: a buffer is smaller than the counts say");
    e.grow(e.nodes, sizeof(raycache::shared::raycache_rsh_node));
    e.grow(e.spheres, 16);
    e.mark(c, phase_none);
    const VkBufferCopy copy{std::uint64_t{count_word} * 4, std::uint64_t{ctl_rays} * 4, 4};
    vkCmdCopyBuffer(c.handle(), counts.handle(), e.control->handle(), 1, &copy);
    c.barrier();
    const ScanLayout layout = scan_layout(max_elements);
    Push p;
    p.capacity = max_elements, p.off1 = layout.off1, p.off2 = layout.off2, p.off3 = layout.off3;
    p.count = scale, p.arg = plan_prefix_sum;
    // The engine's passes with the caller's flags (binding 7) and sums (binding 8).
    auto bound = [&](const vk::ComputePipeline& pipe, const Push& q, std::uint32_t slot, bool indirect) {
        std::initializer_list<vk::Resource> resources = {*e.control, *e.control, *e.control, *e.spheres, *e.nodes,
                                                         *e.pairs[0], *e.pairs[1], flags, sums, *e.control};
        if (indirect) c.dispatch_indirect(pipe, resources, &q, sizeof q, *e.control, 4 * (ctl_args + 3 * slot));
        else c.dispatch(pipe, resources, &q, sizeof q, 1);
        c.barrier();
    };
    bound(*e.plan, p, 0, false);
    for (std::uint32_t k = 0; k < 3; ++k) {
        p.arg = k;
        bound(*e.scan, p, arg_scan0 + k, true);
    }
    for (std::uint32_t k : {1u, 0u}) {
        p.arg = k;
        bound(*e.scan_add, p, k == 1 ? arg_add1 : arg_add0, true);
    }
    e.mark(c, phase_none);
}

void RshEngine::record_trace(vk::Commands& c, const vk::Buffer& rays, std::uint32_t ray_capacity, const vk::Buffer& counts,
                             std::uint32_t count_word, const vk::Buffer& primitives, std::uint32_t primitive_count,
                             const vk::Buffer& hits) {
    using namespace raycache::shared;
    Impl& e = *impl_;
    if (!e.recording) throw std::logic_error("ray-space hierarchy: record_trace() outside begin() .. end()");
    if (rays.size() < std::uint64_t{ray_capacity} * sizeof(raycache_rsh_ray) ||
        primitives.size() < std::uint64_t{primitive_count} * sizeof(raycache_rsh_primitive) ||
        hits.size() < std::uint64_t{ray_capacity} * sizeof(raycache_rsh_hit) || counts.size() < (std::uint64_t{count_word} + 1) * 4)
        throw std::invalid_argument("ray-space hierarchy: a buffer is smaller than its count says");
    int levels = 0;
    while ((std::uint64_t{1} << (2 * levels)) < ray_capacity) ++levels;
    if (levels > 12) throw std::invalid_argument("ray-space hierarchy: more than 4^12 rays");
    e.recorded_levels = std::max(e.recorded_levels, static_cast<std::uint32_t>(levels));
    const std::uint32_t leaves = 1u << (2 * levels);
    const std::uint32_t leaf_first = raycache_rsh_level_first(levels);
    e.grow(e.nodes, std::uint64_t{raycache_rsh_level_first(levels + 1)} * sizeof(raycache_rsh_node));
    if (!e.spheres || e.spheres->size() < std::uint64_t{primitive_count} * 16) e.spheres_of = nullptr; // a new buffer: no spheres yet
    e.grow(e.spheres, std::uint64_t{primitive_count} * 16);

    Push base;
    base.capacity = e.settings.pair_capacity;
    base.off1 = e.off1, base.off2 = e.off2, base.off3 = e.off3;
    // Every pass binds the same ten buffers; `in` picks which pair buffer is this level's input.
    auto direct = [&](const vk::ComputePipeline& pipe, int in, const Push& p, std::uint32_t groups) {
        c.dispatch(pipe, {*e.control, rays, primitives, *e.spheres, *e.nodes, *e.pairs[in], *e.pairs[1 - in], *e.flags,
                          *e.scan_words, hits}, &p, sizeof p, groups);
    };
    // Indirect: the group counts at control word `word`, or at argument slot `slot`.
    auto indirect_at = [&](const vk::ComputePipeline& pipe, int in, const Push& p, std::uint32_t word) {
        c.dispatch_indirect(pipe, {*e.control, rays, primitives, *e.spheres, *e.nodes, *e.pairs[in], *e.pairs[1 - in],
                                   *e.flags, *e.scan_words, hits}, &p, sizeof p, *e.control, 4 * std::uint64_t{word});
    };
    auto indirect = [&](const vk::ComputePipeline& pipe, int in, const Push& p, std::uint32_t slot) {
        indirect_at(pipe, in, p, ctl_args + 3 * slot);
    };

    // 1-2. The ray count where the passes read it; bounding spheres, leaves, levels bottom-up; hits emptied.
    e.mark(c, phase_none); // what the caller recorded before is none of the engine's phases
    const VkBufferCopy copy{std::uint64_t{count_word} * 4, std::uint64_t{ctl_rays} * 4, 4};
    vkCmdCopyBuffer(c.handle(), counts.handle(), e.control->handle(), 1, &copy);
    vkCmdFillBuffer(c.handle(), hits.handle(), 0, std::uint64_t{ray_capacity} * sizeof(raycache_rsh_hit), RAYCACHE_RSH_NO_HIT);
    c.barrier();
    Push p = base;
    // The primitives' bounding spheres, once a recording (the primitives do not change during one).
    if (primitive_count > 0 && (e.spheres_of != &primitives || e.spheres_count != primitive_count)) {
        p.count = primitive_count, p.arg = 0;
        direct(*e.prepare, 0, p, vk::group_count(primitive_count, 64));
        e.spheres_of = &primitives, e.spheres_count = primitive_count;
    }
    // The leaves and levels are sized on the device by the ray count: the nodes that cover a slot.
    p = base;
    p.count = static_cast<std::uint32_t>(levels), p.arg = plan_build;
    direct(*e.plan, 0, p, 1);
    c.barrier();
    p = base;
    p.arg = 1, p.parent_first = leaves, p.child_first = leaf_first;
    indirect_at(*e.prepare, 0, p, ctl_build_args + 3 * static_cast<std::uint32_t>(levels));
    c.barrier();
    for (int l = levels - 1; l >= 0; --l) {
        p = base;
        p.parent_first = raycache_rsh_level_first(l), p.child_first = raycache_rsh_level_first(l + 1);
        p.count = 1u << (2 * l);
        p.arg = static_cast<std::uint32_t>(levels - l); // a node of level l spans 4^(levels - l) slots
        indirect_at(*e.build, 0, p, ctl_build_args + 3 * static_cast<std::uint32_t>(l));
        c.barrier();
    }
    e.mark(c, phase_build);

    // 3-4. Batches of primitives, each as big as this trace's batch size, the last the rest.
    const std::uint32_t trace = std::min(e.recorded_traces++, acc_trace_count - 1); // later ones share the last slot
    if (e.trace_batch.size() <= trace) {
        e.trace_batch.resize(trace + 1, e.settings.pair_capacity);
        e.trace_primitives.resize(trace + 1, 0);
    }
    e.trace_primitives[trace] = primitive_count;
    const std::uint32_t batch = e.trace_batch[trace];
    for (std::uint32_t first = 0; first < primitive_count; first += batch) {
        const std::uint32_t count = std::min(batch, primitive_count - first);
        ++e.recorded_batches;
        int in = 0;
        p = base;
        p.count = count, p.arg = first;
        direct(*e.root, in, p, vk::group_count(count, 64));
        c.barrier();
        e.mark(c, phase_compaction);
        for (int l = 0; l < levels; ++l) {
            p = base;
            p.parent_first = raycache_rsh_level_first(l), p.child_first = raycache_rsh_level_first(l + 1);
            p.arg = static_cast<std::uint32_t>(l) | (l == 0 ? plan_first : 0u);
            p.count = trace; // the plan pass accumulates per trace
            direct(*e.plan, in, p, 1);
            c.barrier();
            e.mark(c, phase_compaction);
            indirect(*e.traverse, in, p, arg_traverse);
            c.barrier();
            e.mark(c, phase_traverse);
            for (std::uint32_t k = 0; k < 3; ++k) {
                p.arg = k;
                indirect(*e.scan, in, p, arg_scan0 + k);
                c.barrier();
            }
            for (std::uint32_t k : {1u, 0u}) {
                p.arg = k;
                indirect(*e.scan_add, in, p, k == 1 ? arg_add1 : arg_add0);
                c.barrier();
            }
            indirect(*e.scatter, in, p, arg_scatter);
            c.barrier();
            e.mark(c, phase_compaction);
            in = 1 - in;
        }
        p = base;
        p.arg = plan_final | (levels == 0 ? plan_first : 0u);
        p.count = trace;
        direct(*e.plan, in, p, 1);
        c.barrier();
        e.mark(c, phase_compaction);
        p.child_first = leaf_first;
        indirect(*e.final_pass, in, p, arg_final);
        c.barrier();
        e.mark(c, phase_final);
    }
}

RshStats RshEngine::trace(const vk::Buffer& rays, std::uint32_t ray_count, const vk::Buffer& primitives,
                          std::uint32_t primitive_count, const vk::Buffer& hits) {
    using namespace raycache::shared;
    Impl& e = *impl_;
    const auto start = std::chrono::steady_clock::now();
    if (rays.size() < std::uint64_t{ray_count} * sizeof(raycache_rsh_ray) ||
        primitives.size() < std::uint64_t{primitive_count} * sizeof(raycache_rsh_primitive) ||
        hits.size() < std::uint64_t{ray_count} * sizeof(raycache_rsh_hit))
        throw std::invalid_argument("ray-space hierarchy: a buffer is smaller than its count says");
    if (ray_count == 0) return RshStats{};
    e.grow(e.count_word, 4);
    e.count_word->upload(&ray_count, 4);
    RshStats total;
    for (;;) { // again, with the lowered batch size, while a batch overflows
        e.context.submit([&](vk::Commands& c) {
            begin(c);
            record_trace(c, rays, ray_count, *e.count_word, 0, primitives, primitive_count, hits);
        });
        const RshStats s = end();
        total.overflows += s.overflows;
        total.cone_sphere_tests += s.cone_sphere_tests; // overflowed recordings included
        if (s.overflows > 0) continue;
        const std::uint32_t overflows = total.overflows;
        const std::uint64_t tests = total.cone_sphere_tests;
        total = s;
        total.overflows = overflows;
        total.cone_sphere_tests = tests;
        break;
    }
    total.wall_ms = ms_since(start);
    return total;
}

} // namespace rcx::gpu
