// dsoc-inspect: pictures of one client's view of the world (docs/pictures.md).
// From a map and either a live in-process run of the server's world and culling
// policy, or a replication trace, writes into --out:
//   plan.png                      top-down plan at --tick (footprints, eye, eye region,
//                                 entities coloured by state, TBV boxes)
//   pyramid-L<level>.png          the z-pyramid's six cube faces side by side
//   pyramid-L<level>-<face>.png   each face alone (px nx py ny pz nz)
//   frames/plan-NNNN.png          --frames plans, --frame-every ticks apart (turn them
//                                 into an animation with any tool; docs/pictures.md)
//   frames/sheet.png              all frames in one picture, --sheet-columns per row
//   view.json                     the counts behind plan.png
// Every image carries a title (map, client, tick, policy, run) and a legend (what each
// colour means; plans also a scale bar in world units; pyramids their faces' names).
// Exit status (dsoc/cli/program.hpp): 0 written, 1 a trace or file failed (message on
// stderr), 2 bad usage or a --map that does not load.

#include "dsoc/cli/choice_option.hpp"
#include "dsoc/cli/program.hpp"
#include "dsoc/cli/setting_option.hpp"
#include "dsoc/inspect/captioned.hpp"
#include "dsoc/inspect/depth_view.hpp"
#include "dsoc/inspect/live_source.hpp"
#include "dsoc/inspect/plan_view.hpp"
#include "dsoc/inspect/png_io.hpp"
#include "dsoc/inspect/trace_source.hpp"
#include "dsoc/maps/map_source.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <bit>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <tuple>

namespace {

using namespace dsoc;

struct Options {
    std::string map;
    std::string trace;
    std::string out;
    std::int64_t client = -1;
    std::uint64_t tick = 90;
    int frames = 0;
    int frame_every = 3;
    float frame_crop = 0.0f;
    int sheet_columns = 5;
    inspect::LiveOptions live;
    inspect::PlanStyle plan;
    float cut_above_eye = 64.0f;
    bool no_cut = false;
    std::string pyramid = "auto";
    int level = 0;
    int face_resolution = 64;
    inspect::DepthStyle depth;
};

/// Something went wrong writing or reading: message on stderr, exit status 1.
struct Failure {
    std::string message;
};

void save(const inspect::Image& image, const std::filesystem::path& path) {
    if (const std::string error = inspect::write_png(image, path.string()); !error.empty()) {
        throw Failure{error};
    }
    std::cout << "wrote " << path.string() << " (" << image.width() << " x " << image.height()
              << ")\n";
}

inspect::PlanStyle plan_style(const Options& o, const inspect::ClientView& view) {
    inspect::PlanStyle style = o.plan;
    if (!o.no_cut && std::isnan(style.cut_above)) {
        style.cut_above = view.eye.z + o.cut_above_eye;
    }
    return style;
}

nlohmann::json summary(const inspect::ClientView& v) {
    using inspect::EntityState;
    std::set<std::tuple<float, float, float, float, float, float>> tbvs;
    for (const auto& e : v.entities) {
        if (e.state == EntityState::hidden_tbv) {
            tbvs.emplace(e.tbv.min.x, e.tbv.min.y, e.tbv.min.z, e.tbv.max.x, e.tbv.max.y,
                         e.tbv.max.z);
        }
    }
    nlohmann::json j;
    j["tick"] = v.tick;
    j["client"] = v.client;
    j["eye"] = {v.eye.x, v.eye.y, v.eye.z};
    if (!v.eye_region.is_empty()) {
        j["eye_region"] = {{"min", {v.eye_region.min.x, v.eye_region.min.y, v.eye_region.min.z}},
                           {"max", {v.eye_region.max.x, v.eye_region.max.y, v.eye_region.max.z}}};
    }
    j["entities"] = v.entities.size();
    for (const EntityState s : inspect::kEveryEntityState) {
        j["states"][inspect::to_string(s)] = v.count(s);
    }
    j["distinct_tbv_boxes"] = tbvs.size();
    nlohmann::json list = nlohmann::json::array();
    for (const auto& e : v.entities) {
        nlohmann::json item = {{"id", e.id},
                               {"state", inspect::to_string(e.state)},
                               {"min", {e.box.min.x, e.box.min.y, e.box.min.z}},
                               {"max", {e.box.max.x, e.box.max.y, e.box.max.z}}};
        if (!e.tbv.is_empty()) {
            item["tbv"] = {{"min", {e.tbv.min.x, e.tbv.min.y, e.tbv.min.z}},
                           {"max", {e.tbv.max.x, e.tbv.max.y, e.tbv.max.z}}};
        }
        list.push_back(std::move(item));
    }
    j["entity_list"] = std::move(list);
    return j;
}

/// One view after another, from either input.
class ViewSource {
public:
    virtual ~ViewSource() = default;
    /// The first view at or after `tick`; throws Failure when there is none.
    virtual inspect::ClientView at(std::uint64_t tick) = 0;
    [[nodiscard]] virtual const visibility::OccluderScene& scene() const = 0;
    [[nodiscard]] virtual const std::vector<inspect::Footprint>& footprints() const = 0;
    [[nodiscard]] virtual visibility::Aabb bounds() const = 0;
    /// What titles name: the map, the policy, where the views come from.
    [[nodiscard]] virtual inspect::RunInfo run() const = 0;
};

class LiveViews final : public ViewSource {
public:
    LiveViews(std::string name, std::shared_ptr<const maps::Map> map,
              const inspect::LiveOptions& options)
        : name_(std::move(name)), options_(options), map_(map), sim_(map, options),
          footprints_(inspect::footprints(map->occluders)) {}
    inspect::ClientView at(std::uint64_t tick) override {
        while (sim_.tick() < std::max<std::uint64_t>(tick, 1)) {
            sim_.advance();
        }
        return sim_.view();
    }
    [[nodiscard]] const visibility::OccluderScene& scene() const override { return *sim_.scene(); }
    [[nodiscard]] const std::vector<inspect::Footprint>& footprints() const override {
        return footprints_;
    }
    [[nodiscard]] visibility::Aabb bounds() const override { return map_->bounds; }
    [[nodiscard]] inspect::RunInfo run() const override {
        return {name_, std::string(interest::name_of(options_.policy)), options_.tick_rate, false,
                "live: " + std::to_string(options_.bots) + " bots, " +
                    std::to_string(options_.tick_rate) + " Hz, " +
                    std::to_string(options_.latency_allowance_ms) +
                    " ms latency allowance, culler " +
                    std::string(interest::name_of(options_.culler)) + ", seed " +
                    std::to_string(options_.seed)};
    }

private:
    std::string name_;
    inspect::LiveOptions options_;
    std::shared_ptr<const maps::Map> map_;
    inspect::LiveSimulation sim_;
    std::vector<inspect::Footprint> footprints_;
};

class TraceViews final : public ViewSource {
public:
    TraceViews(const std::string& path, std::optional<std::uint32_t> client)
        : path_(path), client_(client) {
        std::string error;
        if (!source_.open(path, error)) {
            throw Failure{error};
        }
        footprints_ = inspect::footprints(source_.occluders());
    }
    inspect::ClientView at(std::uint64_t tick) override {
        inspect::ClientView view;
        std::string error;
        if (!source_.next_view(tick, client_, view, error)) {
            throw Failure{error.empty() ? "the trace has no tick >= " + std::to_string(tick) +
                                              " listing the client"
                                        : error};
        }
        return view;
    }
    [[nodiscard]] const visibility::OccluderScene& scene() const override {
        return *source_.scene();
    }
    [[nodiscard]] const std::vector<inspect::Footprint>& footprints() const override {
        return footprints_;
    }
    [[nodiscard]] visibility::Aabb bounds() const override { return source_.bounds(); }
    [[nodiscard]] const trace::TraceHeader& header() const { return source_.header(); }
    [[nodiscard]] inspect::RunInfo run() const override {
        return {header().map, header().policy, header().tick_rate, true,
                "trace " + std::filesystem::path(path_).filename().string() + ": " +
                    std::to_string(header().tick_rate) + " Hz, lookahead " +
                    std::to_string(header().lookahead_ticks) + " ticks"};
    }

private:
    std::string path_;
    inspect::TraceSource source_;
    std::optional<std::uint32_t> client_;
    std::vector<inspect::Footprint> footprints_;
};

/// pyramid-L<level>.png (the six faces, labelled) and one file per face, each with its
/// title and the depth legend.
void write_pyramid(const Options& o, const std::string& mode, const ViewSource& source,
                   const inspect::ClientView& view, const std::filesystem::path& out) {
    const visibility::OccluderScene& scene = source.scene();
    inspect::DepthPyramid pyramid;
    visibility::OcclusionBuffer point({o.face_resolution});
    visibility::RegionOcclusionBuffer region({o.face_resolution});
    if (mode == "region") {
        region.build(view.eye_region, scene.world, scene.bsp);
        pyramid = inspect::DepthPyramid::of(region);
    } else {
        point.build(view.eye, scene.world, scene.bsp);
        pyramid = inspect::DepthPyramid::of(point);
    }
    if (o.level < 0 || o.level >= pyramid.levels) {
        throw Failure{"--level " + std::to_string(o.level) + " is outside 0.." +
                      std::to_string(pyramid.levels - 1) + " for --face-resolution " +
                      std::to_string(o.face_resolution)};
    }
    const int texels = o.face_resolution >> o.level;
    const std::string what = std::string("z-pyramid from the ") +
                             (mode == "region" ? "reachable eye region" : "present eye") +
                             ", level " + std::to_string(o.level) + " (" + std::to_string(texels) +
                             " x " + std::to_string(texels) + " texels a face)";
    const auto face_what = [&](int f) {
        return std::string(inspect::kFaceLabels[f]) + " face of the " + mode +
               " z-pyramid, level " + std::to_string(o.level);
    };
    const inspect::RunInfo run = source.run();
    const std::string stem = "pyramid-L" + std::to_string(o.level);
    save(inspect::captioned_depth(inspect::render_labeled_depth_strip(pyramid, o.level, o.depth),
                                  run, view, what, o.depth),
         out / (stem + ".png"));
    for (int f = 0; f < 6; ++f) {
        save(inspect::captioned_depth(inspect::render_depth_face(pyramid, f, o.level, o.depth), run,
                                      view, face_what(f), o.depth),
             out / (stem + "-" + inspect::kFaceNames[f] + ".png"));
    }
}

/// frames/plan-NNNN.png, --frame-every ticks apart from `first`, each cropped to
/// --frame-crop around the eye when given and labelled with its tick inside, under one
/// caption naming the whole sequence (so that every frame has the same size); and
/// frames/sheet.png with all of them under that caption.
void write_frames(const Options& o, ViewSource& source, const visibility::Aabb& bounds,
                  const inspect::ClientView& first, const std::filesystem::path& dir) {
    std::filesystem::create_directories(dir);
    const inspect::RunInfo run = source.run();
    std::vector<inspect::Image> frames;
    inspect::ClientView last = first;
    std::uint64_t tick = first.tick;
    for (int i = 0; i < o.frames; ++i) {
        const inspect::ClientView v = i == 0 ? first : source.at(tick);
        tick = v.tick + static_cast<std::uint64_t>(o.frame_every);
        const inspect::PlanStyle style = plan_style(o, v);
        inspect::Image image = inspect::render_plan(source.footprints(), bounds, v, style);
        if (o.frame_crop > 0.0f) {
            const inspect::PlanFrame frame(bounds, style);
            const int half = static_cast<int>(std::ceil(o.frame_crop / style.units_per_pixel));
            image = inspect::Image::cropped(image, frame.pixel_x(v.eye.x) - half,
                                            frame.pixel_y(v.eye.y) - half, 2 * half + 1,
                                            2 * half + 1, inspect::kPalette.background);
        }
        frames.push_back(inspect::labeled_frame(std::move(image), run, v));
        last = v;
    }
    const inspect::PlanStyle style = plan_style(o, first);
    for (std::size_t i = 0; i < frames.size(); ++i) {
        char name[32];
        std::snprintf(name, sizeof name, "plan-%04zu.png", i);
        save(inspect::captioned_frames(frames[i], run, first, last, style), dir / name);
    }
    save(inspect::captioned_frames(
             inspect::Image::grid(frames, o.sheet_columns, 4, inspect::Rgb{0, 0, 0}), run, first,
             last, style),
         dir / "sheet.png");
}

int run(const Options& o) {
    const std::filesystem::path out(o.out);
    std::filesystem::create_directories(out);
    std::unique_ptr<ViewSource> source;
    std::string mode = o.pyramid;
    if (!o.trace.empty()) {
        std::optional<std::uint32_t> client;
        if (o.client >= 0) {
            client = static_cast<std::uint32_t>(o.client);
        }
        auto views = std::make_unique<TraceViews>(o.trace, client);
        if (!o.map.empty() && o.map != views->header().map) {
            std::cerr << "dsoc-inspect: note: --map " << o.map << " but the trace was made on "
                      << views->header().map << "; drawing the trace's occluders\n";
        }
        source = std::move(views);
        if (mode == "auto") {
            mode = "eye"; // a trace has no eye region
        } else if (mode == "region") {
            throw Failure{"--pyramid region needs the live mode: a trace records no eye region"};
        }
    } else {
        auto map = maps::load_map(o.map, maps::MapSearch::from_environment());
        if (!map) {
            std::cerr << "dsoc-inspect: "
                      << cli::map_load_failure("--map", o.map, map.error().message()) << '\n';
            return cli::exit_usage;
        }
        auto shared = std::make_shared<const maps::Map>(std::move(map).value());
        inspect::LiveOptions live = o.live;
        if (o.client >= 0) {
            live.viewer_entity = static_cast<std::uint32_t>(o.client);
        }
        source = std::make_unique<LiveViews>(o.map, shared, live);
        if (mode == "auto") {
            mode = "region";
        }
    }
    const visibility::Aabb bounds = source->bounds();

    const inspect::ClientView view = source->at(o.tick);
    const inspect::PlanStyle style = plan_style(o, view);
    save(inspect::captioned_plan(inspect::render_plan(source->footprints(), bounds, view, style),
                                 source->run(), view, style),
         out / "plan.png");
    const nlohmann::json j = summary(view);
    std::ofstream(out / "view.json") << j.dump(1) << '\n';
    nlohmann::json brief = j;
    brief.erase("entity_list");
    std::cout << brief.dump() << '\n';
    if (mode != "none") {
        write_pyramid(o, mode, *source, view, out);
    }
    if (o.frames > 0) {
        write_frames(o, *source, bounds, view, out / "frames");
    }
    return 0;
}

} // namespace

int main(int argc, char** argv) {
    CLI::App app{"dsoc-inspect: PNG pictures of one client's view: a top-down plan (occluders "
                 "shaded by height, the eye and its reachable region, entities coloured by "
                 "state, TBV boxes), the z-pyramid's six cube faces, and frame sequences. "
                 "Input: a live in-process run of the server's world and policy on --map, or "
                 "a replication trace (--trace). Each image carries its title, the legend of its "
                 "colours and (plans) a scale bar. See docs/pictures.md."};
    dsoc::cli::set_up(app, "dsoc-inspect");
    Options o;
    app.add_option("--map", o.map, "map name, file path or gen:city / gen:rooms (live mode)");
    app.add_option("--trace", o.trace, "replication trace to draw instead of a live run");
    app.add_option("--out", o.out, "output directory (created)")->required();
    app.add_option("--client", o.client,
                   "live: the bot (1..bots) the client views from, default 1; trace: the "
                   "client id, default the first listed");
    cli::add_setting(app, "--tick", o.tick,
                     "the tick drawn in plan.png (trace: first recorded >= it)");
    app.add_option("--frames", o.frames, "also write this many plans to frames/")
        ->check(CLI::Range(0, 100000));
    cli::add_setting(app, "--frame-every", o.frame_every, "ticks between frames")
        ->check(CLI::Range(1, 100000));
    cli::add_setting(app, "--frame-crop", o.frame_crop,
                     "frames show only this far around the eye [world units]; 0: the whole map")
        ->check(CLI::NonNegativeNumber);
    cli::add_setting(app, "--sheet-columns", o.sheet_columns, "frames per row of frames/sheet.png")
        ->check(CLI::Range(1, 100));
    cli::add_choice_option(app, "--policy", o.live.policy, "live: dsoc or occlusion");
    app.add_flag("--tbvs", o.live.tbvs,
                 "live: dsoc with the paper's TBVs (off by default), drawn around what they hide");
    cli::add_setting(app, "--bots", o.live.bots, "live: wandering entities (arena-64: 576)");
    cli::add_setting(app, "--tick-rate", o.live.tick_rate, "live: [Hz]");
    cli::add_setting(app, "--latency-ms", o.live.latency_allowance_ms,
                     "live: round trip + interpolation covered [ms]");
    cli::add_choice_option(app, "--culler", o.live.culler, "live: shaft, pyramid or both");
    cli::add_setting(app, "--seed", o.live.seed, "live: bots' seed");
    cli::add_setting(app, "--units-per-pixel", o.plan.units_per_pixel, "plan scale [world units]")
        ->check(CLI::PositiveNumber);
    app.add_option("--cut-above", o.plan.cut_above,
                   "leave out occluders whose bottom is above this z [world units] (default: "
                   "the eye + --cut-above-eye)");
    cli::add_setting(app, "--cut-above-eye", o.cut_above_eye,
                     "default cut height above the eye [world units]");
    app.add_flag("--no-cut", o.no_cut, "draw every occluder (ceilings too)");
    cli::add_setting(app, "--pyramid", o.pyramid,
                     "z-pyramid dumped: region (from the client's reachable eye region, live "
                     "only), eye (from the present eye), none; auto = region live, eye for traces")
        ->check(CLI::IsMember({"auto", "region", "eye", "none"}));
    cli::add_setting(app, "--level", o.level, "pyramid level drawn (0 = finest)");
    cli::add_setting(app, "--face-resolution", o.face_resolution,
                     "pyramid texels per face side (power of two, 8..1024)");
    cli::add_setting(app, "--far-depth", o.depth.far_depth, "depth drawn black [world units]")
        ->check(CLI::PositiveNumber);
    cli::add_setting(app, "--face-pixels", o.depth.face_pixels,
                     "pixels per face side in the images")
        ->check(CLI::Range(8, 4096));
    if (const auto stop = dsoc::cli::parse(app, argc, argv)) {
        return *stop;
    }

    if (o.map.empty() && o.trace.empty()) {
        std::cerr << "dsoc-inspect: give --map (live run) or --trace FILE (see --help)\n";
        return 2;
    }
    if (const auto problems =
            visibility::validate(visibility::RegionOcclusionBufferConfig{o.face_resolution});
        !problems.empty()) {
        std::cerr << "dsoc-inspect: --face-resolution: " << problems.front() << '\n';
        return 2;
    }
    if (o.level < 0 || (o.face_resolution >> o.level) < 1) {
        std::cerr << "dsoc-inspect: --level " << o.level << " is outside 0.."
                  << std::bit_width(static_cast<unsigned>(o.face_resolution)) - 1
                  << " for --face-resolution " << o.face_resolution << '\n';
        return 2;
    }
    if (o.trace.empty()) {
        inspect::LiveOptions live = o.live;
        if (o.client >= 0) {
            live.viewer_entity = static_cast<std::uint32_t>(o.client);
        }
        if (const auto problems = inspect::validate(live); !problems.empty()) {
            for (const auto& p : problems) {
                std::cerr << "dsoc-inspect: " << p << '\n';
            }
            return 2;
        }
    }
    try {
        return run(o);
    } catch (const Failure& f) {
        std::cerr << "dsoc-inspect: " << f.message << '\n';
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "dsoc-inspect: " << e.what() << '\n';
        return 1;
    }
}
