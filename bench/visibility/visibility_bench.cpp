// Usage: visibility_bench [--benchmark_filter=...] [google benchmark flags]
// Scene: make_corridor_world(seed 42, 11 x 10 rooms) (~1,000 brushes), eye in room
// (5, 5) at standing height, 512 player-sized boxes spread over the whole map.
// Before timing, the setup checks that neither backend culls a box the reference
// sees (aborts otherwise), and reports how many boxes each culls.

#include "dsoc/visibility/bsp_tree.hpp"
#include "dsoc/visibility/loose_octree.hpp"
#include "dsoc/visibility/occluder_bvh.hpp"
#include "dsoc/visibility/occluder_grid.hpp"
#include "dsoc/visibility/reference_visibility.hpp"
#include "dsoc/visibility/seeds/occlusion_beams.hpp"
#include "dsoc/visibility/seeds/occlusion_buffer.hpp"
#include "dsoc/visibility/seeds/test_worlds.hpp"
#include "dsoc/visibility/shaft_occlusion.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

namespace dsoc::visibility {
namespace {

struct Scene {
    TestWorld tw;
    BspTree bsp;
    glm::vec3 eye;
    std::vector<Aabb> boxes;
    int reference_hidden = 0;
    int buffer_culled = 0;
    int beams_culled = 0;

    Scene()
        : tw(make_corridor_world(42, 11, 10)),
          eye(5 * 512.0f + 200.0f, 5 * 512.0f + 300.0f, 56.0f) {
        bsp.build(tw.world);
        std::mt19937 rng(7);
        std::uniform_real_distribution<float> unit(0.0f, 1.0f);
        const Aabb area = tw.play_area;
        while (boxes.size() < 512) {
            const glm::vec3 c = area.min + area.size() * glm::vec3(unit(rng), unit(rng), 0.0f) +
                                glm::vec3(0.0f, 0.0f, 28.0f + 100.0f * unit(rng));
            boxes.push_back(Aabb::from_center_half_extents(c, {16.0f, 16.0f, 28.0f}));
        }
        const ReferenceVisibility reference(tw.world);
        OcclusionBuffer buffer;
        buffer.build(eye, tw.world, bsp);
        OcclusionBeams beams;
        beams.build(eye, tw.world, bsp);
        for (const Aabb& b : boxes) {
            const bool seen = reference.test_box(eye, b) == Visibility::visible;
            const bool zb = buffer.test_box(b) == Visibility::occluded;
            const bool bm = beams.test_box(b) == Visibility::occluded;
            if (seen && (zb || bm)) {
                std::fprintf(stderr, "validation failed: a backend culled a visible box\n");
                std::abort();
            }
            reference_hidden += seen ? 0 : 1;
            buffer_culled += zb ? 1 : 0;
            beams_culled += bm ? 1 : 0;
        }
    }
};

const Scene& scene() {
    static const Scene s;
    return s;
}

/// How many of `boxes` `test` (Aabb -> Visibility) proves occluded.
template <class Test>
int count_occluded(const std::vector<Aabb>& boxes, const Test& test) {
    int occluded = 0;
    for (const Aabb& b : boxes) {
        occluded += test(b) == Visibility::occluded;
    }
    return occluded;
}

/// Times `test` over the scene's boxes (items: boxes tested); the counter `name` holds
/// how many it proves occluded.
template <class Test>
void time_box_tests(benchmark::State& state, const Test& test, const char* name) {
    const Scene& s = scene();
    int occluded = 0;
    for (auto _ : state) {
        occluded = count_occluded(s.boxes, test);
        benchmark::DoNotOptimize(occluded);
    }
    state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(s.boxes.size()));
    state.counters[name] = occluded;
}

void report_scene(benchmark::State& state) {
    const Scene& s = scene();
    state.counters["brushes"] = static_cast<double>(s.tw.world.size());
    state.counters["boxes"] = static_cast<double>(s.boxes.size());
    state.counters["ref_hidden"] = s.reference_hidden;
    state.counters["zpyr_culled"] = s.buffer_culled;
    state.counters["beams_culled"] = s.beams_culled;
}

void BM_OcclusionBufferBuild(benchmark::State& state) {
    const Scene& s = scene();
    OcclusionBufferConfig config;
    config.face_resolution = static_cast<int>(state.range(0));
    OcclusionBuffer buffer(config);
    for (auto _ : state) {
        buffer.build(s.eye, s.tw.world, s.bsp);
        benchmark::ClobberMemory();
    }
    state.counters["occluders"] = buffer.stats().occluders_visited;
    state.counters["texels_written"] = static_cast<double>(buffer.stats().texels_written);
    report_scene(state);
}
BENCHMARK(BM_OcclusionBufferBuild)->Arg(32)->Arg(64)->Arg(128)->Unit(benchmark::kMicrosecond);

/// From-region build for a viewer region of +-48 units sideways, +-16 up and down
/// (320 units/s x 150 ms of latency allowance).
void BM_OcclusionBufferBuildRegion(benchmark::State& state) {
    const Scene& s = scene();
    OcclusionBuffer buffer;
    const Aabb region = Aabb::from_center_half_extents(s.eye, {48.0f, 48.0f, 16.0f});
    for (auto _ : state) {
        buffer.build_region(region, s.tw.world, s.bsp);
        benchmark::ClobberMemory();
    }
    state.counters["occluders"] = buffer.stats().occluders_visited;
    state.counters["culled"] =
        count_occluded(s.boxes, [&](const Aabb& b) { return buffer.test_box(b); });
}
BENCHMARK(BM_OcclusionBufferBuildRegion)->Unit(benchmark::kMicrosecond);

void BM_OcclusionBufferTestBox(benchmark::State& state) {
    const Scene& s = scene();
    OcclusionBufferConfig config;
    config.face_resolution = static_cast<int>(state.range(0));
    OcclusionBuffer buffer(config);
    buffer.build(s.eye, s.tw.world, s.bsp);
    time_box_tests(
        state, [&](const Aabb& b) { return buffer.test_box(b); }, "culled");
    state.counters["ns_per_box"] = benchmark::Counter(
        static_cast<double>(state.iterations() * s.boxes.size()),
        benchmark::Counter::kIsRate | benchmark::Counter::kInvert, benchmark::Counter::kIs1000);
}
BENCHMARK(BM_OcclusionBufferTestBox)->Arg(32)->Arg(64)->Arg(128);

void BM_OcclusionBeamsBuild(benchmark::State& state) {
    const Scene& s = scene();
    OcclusionBeams beams;
    for (auto _ : state) {
        beams.build(s.eye, s.tw.world, s.bsp);
        benchmark::ClobberMemory();
    }
    state.counters["beams"] = beams.stats().beams;
}
BENCHMARK(BM_OcclusionBeamsBuild)->Unit(benchmark::kMicrosecond);

void BM_OcclusionBeamsTestBox(benchmark::State& state) {
    const Scene& s = scene();
    OcclusionBeams beams;
    beams.build(s.eye, s.tw.world, s.bsp);
    time_box_tests(
        state, [&](const Aabb& b) { return beams.test_box(b); }, "culled");
}
BENCHMARK(BM_OcclusionBeamsTestBox);

void BM_ReferenceTestBox(benchmark::State& state) {
    const Scene& s = scene();
    const ReferenceVisibility reference(s.tw.world);
    time_box_tests(
        state, [&](const Aabb& b) { return reference.test_box(s.eye, b); }, "hidden");
}
BENCHMARK(BM_ReferenceTestBox)->Unit(benchmark::kMillisecond);

/// One run, one ratio: build + 512 tests with the z-pyramid versus the same 512
/// boxes answered by the brute-force reference, timed back to back.
void BM_SpeedupVersusReference(benchmark::State& state) {
    const Scene& s = scene();
    const ReferenceVisibility reference(s.tw.world);
    OcclusionBuffer buffer;
    double fast_ns = 0.0;
    double slow_ns = 0.0;
    using clock = std::chrono::steady_clock;
    for (auto _ : state) {
        const auto t0 = clock::now();
        buffer.build(s.eye, s.tw.world, s.bsp);
        const int culled =
            count_occluded(s.boxes, [&](const Aabb& b) { return buffer.test_box(b); });
        const auto t1 = clock::now();
        const int hidden =
            count_occluded(s.boxes, [&](const Aabb& b) { return reference.test_box(s.eye, b); });
        const auto t2 = clock::now();
        benchmark::DoNotOptimize(culled + hidden);
        fast_ns += std::chrono::duration<double, std::nano>(t1 - t0).count();
        slow_ns += std::chrono::duration<double, std::nano>(t2 - t1).count();
    }
    state.counters["zpyr_build_and_512_tests_us"] =
        fast_ns / 1000.0 / static_cast<double>(state.iterations());
    state.counters["reference_512_tests_us"] =
        slow_ns / 1000.0 / static_cast<double>(state.iterations());
    state.counters["speedup"] = slow_ns / fast_ns;
    report_scene(state);
}
BENCHMARK(BM_SpeedupVersusReference)->Unit(benchmark::kMillisecond);

/// An octree over the scene's play area (and 256 units around it) for `max_items`.
LooseOctreeConfig octree_config(std::uint32_t max_items) {
    LooseOctreeConfig config;
    config.world_bounds = scene().tw.play_area.expanded(256.0f);
    config.max_items = max_items;
    return config;
}

void BM_OctreeMove(benchmark::State& state) {
    const Scene& s = scene();
    const LooseOctreeConfig config = octree_config(4096);
    LooseOctree tree(config);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    std::vector<Aabb> boxes(config.max_items);
    for (ItemId id = 0; id < config.max_items; ++id) {
        const glm::vec3 c =
            s.tw.play_area.min + s.tw.play_area.size() * glm::vec3(unit(rng), unit(rng), unit(rng));
        boxes[id] = Aabb::from_center_half_extents(c, {16.0f, 16.0f, 28.0f});
        (void)tree.insert(id, boxes[id]);
    }
    // Per-tick player motion: up to 320 units/s at 60 Hz, about 5 units per move.
    std::vector<glm::vec3> steps(1024);
    for (auto& d : steps) {
        d = glm::vec3(unit(rng) - 0.5f, unit(rng) - 0.5f, 0.0f) * 10.0f;
    }
    std::size_t k = 0;
    for (auto _ : state) {
        const ItemId id = static_cast<ItemId>(k % config.max_items);
        const glm::vec3 d = steps[k % steps.size()];
        boxes[id] = {boxes[id].min + d, boxes[id].max + d};
        benchmark::DoNotOptimize(tree.move(id, boxes[id]));
        ++k;
    }
    state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_OctreeMove);

void BM_OctreeCulledTraversal(benchmark::State& state) {
    const Scene& s = scene();
    LooseOctree tree(octree_config(512));
    for (ItemId id = 0; id < 512; ++id) {
        (void)tree.insert(id, s.boxes[id]);
    }
    OcclusionBuffer buffer;
    buffer.build(s.eye, s.tw.world, s.bsp);
    int visible = 0;
    for (auto _ : state) {
        visible = 0;
        tree.traverse_front_to_back(s.eye, buffer, [&](ItemId) { ++visible; });
        benchmark::DoNotOptimize(visible);
    }
    state.counters["visible"] = visible;
}
BENCHMARK(BM_OctreeCulledTraversal)->Unit(benchmark::kMicrosecond);

void BM_BspBuild(benchmark::State& state) {
    // 10 x 10 rooms ~ 1k brushes; 32 x 32 rooms ~ 10k brushes.
    const int rooms = static_cast<int>(state.range(0));
    const TestWorld tw = make_corridor_world(9, rooms, rooms);
    BspTree bsp;
    for (auto _ : state) {
        bsp.build(tw.world);
        benchmark::ClobberMemory();
    }
    state.counters["brushes"] = static_cast<double>(tw.world.size());
    state.counters["depth"] = bsp.depth();
}
BENCHMARK(BM_BspBuild)->Arg(10)->Arg(32)->Unit(benchmark::kMillisecond);

/// Times a fast path `fast` and its slow twin `twin` (each bool(const Triple&)) over
/// the same triples back to back, each iteration: counters ns per call each way, the
/// speed-up and the share of triples blocked. Answers that differ for any triple end
/// the run with an error.
template <class Triple, class Fast, class Twin>
void time_against_twin(benchmark::State& state, const std::vector<Triple>& triples, Fast&& fast,
                       Twin&& twin) {
    std::vector<std::uint8_t> fast_answers(triples.size());
    std::vector<std::uint8_t> twin_answers(triples.size());
    double fast_ns = 0.0;
    double twin_ns = 0.0;
    using clock = std::chrono::steady_clock;
    for (auto _ : state) {
        const auto t0 = clock::now();
        for (std::size_t i = 0; i < triples.size(); ++i) {
            fast_answers[i] = fast(triples[i]) ? 1 : 0;
        }
        const auto t1 = clock::now();
        for (std::size_t i = 0; i < triples.size(); ++i) {
            twin_answers[i] = twin(triples[i]) ? 1 : 0;
        }
        const auto t2 = clock::now();
        if (fast_answers != twin_answers) {
            state.SkipWithError("the two paths disagree");
            break;
        }
        fast_ns += std::chrono::duration<double, std::nano>(t1 - t0).count();
        twin_ns += std::chrono::duration<double, std::nano>(t2 - t1).count();
    }
    const double calls =
        static_cast<double>(state.iterations()) * static_cast<double>(triples.size());
    state.counters["ns_per_call"] = fast_ns / calls;
    state.counters["twin_ns_per_call"] = twin_ns / calls;
    state.counters["speedup"] = twin_ns / fast_ns;
    state.counters["blocked"] =
        static_cast<double>(std::count(fast_answers.begin(), fast_answers.end(), 1)) /
        static_cast<double>(triples.size());
}

/// BM_ShaftBlockedBy*'s 4,096 triples (the same each run): an eye region, a player box
/// 200-2,000 units away along x, and a wall between them whose extent across the shaft
/// is random.
struct ShaftTriple {
    Aabb region, box, wall;
};
std::vector<ShaftTriple> shaft_triples() {
    std::vector<ShaftTriple> triples;
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (int i = 0; i < 4096; ++i) {
        const glm::vec3 eye(0.0f, 300.0f * unit(rng), 40.0f + 20.0f * unit(rng));
        const glm::vec3 eye_reach(32.0f, 32.0f, 8.0f);
        const glm::vec3 at(200.0f + 1800.0f * unit(rng), 300.0f * unit(rng), 24.0f);
        const float x = 0.3f * at.x + 0.4f * at.x * unit(rng);
        const float half = 20.0f + 200.0f * unit(rng);
        const float y = 150.0f + 100.0f * (unit(rng) - 0.5f);
        triples.push_back(
            {Aabb{eye - eye_reach, eye + eye_reach},
             Aabb{at - glm::vec3(15.0f, 15.0f, 24.0f), at + glm::vec3(15.0f, 15.0f, 32.0f)},
             Aabb{glm::vec3(x, y - half, -16.0f),
                  glm::vec3(x + 16.0f, y + half, 80.0f + 200.0f * unit(rng))}});
    }
    return triples;
}

/// One run, one ratio: shaft_blocked_by_box() (four pairs of sides at a time with
/// SSE2) against shaft_blocked_by_box_scalar() over the same 4,096 triples, timed back
/// to back: an eye region, a player box 200-2,000 units away along x, and a wall
/// between them whose extent across the shaft is random (most triples blocked, as the
/// hint's retry of a hidden pair mostly is; the others stop at the first check that
/// fails). Counters: ns per call each way, the speed-up, the blocked share.
void BM_ShaftBlockedByBox(benchmark::State& state) {
    const std::vector<ShaftTriple> triples = shaft_triples();
    time_against_twin(
        state, triples,
        [](const ShaftTriple& t) { return shaft_blocked_by_box(t.region, t.box, t.wall); },
        [](const ShaftTriple& t) { return shaft_blocked_by_box_scalar(t.region, t.box, t.wall); });
}
BENCHMARK(BM_ShaftBlockedByBox);

/// One run, one ratio: shaft_blocked_by() on a solid given by planes (two corner
/// segments at a time with SSE2) against shaft_blocked_by_scalar(), over the same
/// 4,096 triples timed back to back: BM_ShaftBlockedByBox's (shaft_triples()), the walls
/// turned about the vertical by up to 30 degrees with a seventh,
/// bevelled face (a real map's brushes that are not axis boxes take this path).
void BM_ShaftBlockedByPlanes(benchmark::State& state) {
    struct Triple {
        Aabb region, box;
        std::vector<Plane> solid;
    };
    std::vector<Triple> triples;
    std::mt19937 rng(12);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (const ShaftTriple& t : shaft_triples()) {
        const Aabb& wall = t.wall;
        const glm::vec3 c = wall.center();
        const float angle = (unit(rng) - 0.5f) * 1.0472f; // +-30 degrees
        const float cs = std::cos(angle);
        const float sn = std::sin(angle);
        std::vector<Plane> planes = ConvexPolyhedron::from_aabb(wall).planes();
        Plane bevel;
        bevel.normal = glm::normalize(glm::vec3(1.0f, 0.0f, 1.0f));
        bevel.distance = glm::dot(bevel.normal, glm::vec3(wall.max.x, c.y, wall.max.z)) - 4.0f;
        planes.push_back(bevel);
        for (Plane& p : planes) { // turned about the wall's centre
            const float offset = p.distance - glm::dot(p.normal, c);
            p.normal = glm::vec3(cs * p.normal.x - sn * p.normal.y,
                                 sn * p.normal.x + cs * p.normal.y, p.normal.z);
            p.distance = glm::dot(p.normal, c) + offset;
        }
        triples.push_back({t.region, t.box, std::move(planes)});
    }
    time_against_twin(
        state, triples, [](const Triple& t) { return shaft_blocked_by(t.region, t.box, t.solid); },
        [](const Triple& t) { return shaft_blocked_by_scalar(t.region, t.box, t.solid); });
}
BENCHMARK(BM_ShaftBlockedByPlanes);

/// One run, one ratio: is a centre segment blocked by some occluder (segment_through_box()
/// on its solid box), answered by OccluderBvh::any_touching_segment() against the grid
/// walk (OccluderGrid::any_along_segment()) the shaft stage used alone before, over the
/// same 4,096 segments timed back to back: between random points 40-60 units above the
/// ground of a generated city of 12 x 12 blocks, five clear ones to one blocked (as the
/// shaft stage's checks find them on city-1k). Counters: ns per call each way, the
/// speed-up, the blocked share.
void BM_CentreSegmentTreeAgainstWalk(benchmark::State& state) {
    const TestWorld tw = make_city_world(5, 12, 12);
    const OccluderGrid grid(tw.world);
    const OccluderBvh bvh(tw.world);
    struct Segment {
        glm::vec3 from, to;
    };
    std::vector<Segment> segments;
    std::mt19937 rng(13);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    const Aabb& area = tw.play_area;
    const auto street_point = [&] {
        return glm::vec3(area.min.x + (area.max.x - area.min.x) * unit(rng),
                         area.min.y + (area.max.y - area.min.y) * unit(rng),
                         area.min.z + 40.0f + 20.0f * unit(rng));
    };
    const auto blocks = [&](const Segment& s) {
        const SegmentRay ray = SegmentRay::between(s.from, s.to);
        return [&tw, ray](OccluderId id) {
            const Aabb& solid = tw.world.solid_box(id);
            return !solid.is_empty() && segment_through_box(ray, solid);
        };
    };
    // Five clear segments to one blocked, as the tree's checks in the shaft stage find them.
    ReferenceVisibility reference(tw.world);
    int clear = 0;
    int blocked = 0;
    while (clear + blocked < 4096) {
        const Segment s{street_point(), street_point()};
        const bool is_blocked = reference.segment_blocked(s.from, s.to);
        if (is_blocked ? blocked * 5 < clear : clear < 4096 * 5 / 6) {
            segments.push_back(s);
            (is_blocked ? blocked : clear) += 1;
        }
    }
    OccluderGrid::Scratch scratch;
    time_against_twin(
        state, segments,
        [&](const Segment& s) { return bvh.any_touching_segment(s.from, s.to, blocks(s)); },
        [&](const Segment& s) { return grid.any_along_segment(s.from, s.to, scratch, blocks(s)); });
}
BENCHMARK(BM_CentreSegmentTreeAgainstWalk);

} // namespace
} // namespace dsoc::visibility

BENCHMARK_MAIN();
