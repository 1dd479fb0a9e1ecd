// `accelbench render`: the interactive side of the harness — one model, one accelerator,
// one image, with everything it measured.
#include "commands/args.h"
#include "commands/cli.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "accelbench/accel/registry.h"
#include "accelbench/base/unknown_name.h"
#include "accelbench/render/renderer.h"
#include "accelbench/scene/mesh_io.h"
#include "models/model_registry.h"
#include "util/cost_image.h"

namespace accelbench {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

const char* kRenderUsage =
    "usage: accelbench render --model NAME|PATH|procedural:KIND[,k=v...] --accel NAME\n"
    "         [--param k=v ...] [--out img.png] [--width W] [--height H] [--spp N]\n"
    "         [--no-light] [--threads N] [--fp-mode ieee|ftz_daz] [--cost-out PREFIX]\n"
    "         [--plugin PATH ...]\n"
    "--plugin PATH loads the structures of a plugin (accelbench_plugin.h), so --accel can name them\n"
    "--cost-out PREFIX writes PREFIX-node_visits.png, PREFIX-prim_tests.png (heatmaps, inferno,\n"
    "each scaled to its own maximum) and PREFIX-cost.csv (per-pixel values)\n";

std::pair<std::string, std::string> split_kv(const std::string& kv) {
    auto eq = kv.find('=');
    if (eq == std::string::npos || eq == 0) throw ParamError("expected k=v, got '" + kv + "'");
    return {kv.substr(0, eq), kv.substr(eq + 1)};
}

}  // namespace

LoadedModel resolve_model(const std::string& text, const ModelRegistry& registry, const RenderSettings& render) {
    ModelSpec spec;
    if (text.rfind("procedural:", 0) == 0) {
        // procedural:KIND[,k=v,k=v]
        std::string rest = text.substr(11);
        spec.kind = ModelSpec::Kind::Procedural;
        spec.name = rest.substr(0, rest.find(','));
        for (size_t pos = rest.find(','); pos != std::string::npos;) {
            size_t next = rest.find(',', pos + 1);
            auto kv = split_kv(rest.substr(pos + 1, next == std::string::npos ? std::string::npos : next - pos - 1));
            if (auto [it, fresh] = spec.procedural_params.insert(kv); !fresh)
                throw ParamError("--model " + text + ": parameter '" + kv.first + "' is given twice (" + kv.first +
                                 "=" + it->second + ", then " + kv.first + "=" + kv.second + ")");
            pos = next;
        }
    } else if (registry.find(text)) {
        spec.kind = ModelSpec::Kind::Registry;
        spec.name = text;
    } else if (std::filesystem::exists(text)) {
        spec.kind = ModelSpec::Kind::Path;
        spec.name = spec.resolved_path = text;
    } else {
        std::string names;
        for (const auto& e : registry.entries()) names += (names.empty() ? "" : ", ") + e.name;
        throw std::runtime_error("model '" + text + "' is not a registry name (" + names +
                                 "), not procedural:KIND, and no such file exists");
    }
    return load_model(spec, registry, render);
}

int render_command(int argc, char** argv) {
    std::string model, accel_name, out, cost_out, param, fp_mode, plugin;
    std::vector<std::string> plugins;
    std::map<std::string, std::string> params;
    TraceRequest req;
    req.counts = CountMode::Totals;
    RenderSettings& r = req.settings;
    Args args("render", kRenderUsage, argc, argv);
    const auto each = [&] {
        if (args.value("--param", param)) {
            try {
                auto [k, v] = split_kv(param);
                if (!params.emplace(k, v).second) throw ArgError("--param " + k + " given twice");
            } catch (const ParamError& e) {
                throw ArgError(e.what());
            }
        } else if (args.value("--plugin", plugin)) {
            plugins.push_back(plugin);
        } else if (args.flag("--no-light")) {
            r.light = false;
        } else if (!(args.value("--model", model) || args.value("--accel", accel_name) || args.value("--out", out) ||
                     args.value("--cost-out", cost_out) || args.value("--fp-mode", fp_mode) ||
                     args.value("--width", r.width, 1, 16384) || args.value("--height", r.height, 1, 16384) ||
                     args.value("--spp", r.spp, 1, 4096) || args.value("--threads", r.threads, 1, 1024))) {
            args.unknown();
        }
    };
    if (auto code = args.walk(each)) return *code;
    if (model.empty() || accel_name.empty()) return args.error("--model and --accel are required");
    if (auto code = load_plugins("render", plugins)) return *code;
    if (!fp_mode.empty()) {
        const auto mode = parse_fp_mode(fp_mode);
        const std::vector<std::string> names(fp_mode_names().begin(), fp_mode_names().end());
        if (!mode) return args.error("--fp-mode: " + unknown_name("fp_mode", fp_mode, names));
        r.fp_mode = *mode;
    }
    const AcceleratorInfo* info = find_accelerator(accel_name);
    if (!cost_out.empty() && info && !info->counts_traversal)
        return args.error("--cost-out needs traversal counters, which " + accel_name + " does not expose");
    req.settings.shading = !out.empty();  // no image asked for: no shading work

    std::unique_ptr<Accelerator> accel;
    ParamSet resolved;
    try {
        accel = make_accelerator(accel_name, params, &resolved);
    } catch (const ParamError& e) {
        std::fprintf(stderr, "accelbench render: %s\n", e.what());
        return 2;
    }
    try {
        const auto t_load = Clock::now();
        ModelRegistry registry = ModelRegistry::load_default();
        LoadedModel m = resolve_model(model, registry, req.settings);
        req.light = m.light;
        req.albedo = m.albedo;
        std::printf("model      %s: %zu triangles, %zu vertices (loaded in %.3f s)\n", m.scene.name.c_str(),
                    m.scene.triangle_count(), m.scene.vertex_count(), seconds_since(t_load));
        std::printf("accel      %s %s\n", accel_name.c_str(), resolved.canonical().c_str());

        const auto t_build = Clock::now();
        accel->build(m.scene);
        const double build_s = seconds_since(t_build);

        // The timed render traces without counters; a second, counting pass gives the
        // statistics (counting would otherwise slow the timed pass).
        TraceRequest timed = req;
        timed.counts = CountMode::Off;
        const auto t_render = Clock::now();
        TraceOutput r = render(*accel, m.scene, m.camera, timed);
        const double render_s = seconds_since(t_render);
        TraceRequest counting = req;
        counting.settings.shading = false;
        if (!cost_out.empty()) counting.counts = CountMode::PerPixel;
        TraceOutput c = render(*accel, m.scene, m.camera, counting);

        BuildStats bs = accel->build_stats();
        auto opt = [](const std::optional<uint64_t>& v) { return v ? std::to_string(*v) : std::string("n/a"); };
        std::printf("build      %.4f s\n", build_s);
        std::printf("render     %.4f s  (%dx%d, %d spp, light %s, %d thread%s, fp_mode %s)\n", render_s,
                    req.settings.width, req.settings.height, req.settings.spp, req.settings.light ? "on" : "off",
                    req.settings.threads, req.settings.threads == 1 ? "" : "s",
                    std::string(fp_mode_name(req.settings.fp_mode)).c_str());
        std::printf("rays       %llu primary, %llu hits; %llu shadow, %llu occluded\n", (unsigned long long)r.rays,
                    (unsigned long long)r.hits, (unsigned long long)r.shadow_rays, (unsigned long long)r.shadow_hits);
        std::printf("speed      %.2f Mrays/s (primary + shadow)\n", double(r.rays + r.shadow_rays) / render_s * 1e-6);
        std::printf("tree       nodes %s, leaves %s, max depth %s, memory %s bytes\n", opt(bs.nodes).c_str(),
                    opt(bs.leaves).c_str(), opt(bs.max_depth).c_str(), opt(bs.memory_bytes).c_str());
        if (bs.sah_cost) std::printf("sah cost   %.4f\n", *bs.sah_cost);
        for (const auto& [k, v] : bs.extra) std::printf("extra      %s = %g\n", k.c_str(), v);
        if (!info->counts_traversal) {
            std::printf("counters   n/a (%s does not expose traversal statistics)\n", accel_name.c_str());
        } else {
            const RayStats& p = c.primary_stats;
            const RayStats& s = c.shadow_stats;
            std::printf("counters   primary: %llu prim tests, %llu node visits, %llu box tests\n",
                        (unsigned long long)p.prim_tests, (unsigned long long)p.node_visits,
                        (unsigned long long)p.box_tests);
            std::printf("           shadow:  %llu prim tests, %llu node visits, %llu box tests\n",
                        (unsigned long long)s.prim_tests, (unsigned long long)s.node_visits,
                        (unsigned long long)s.box_tests);
        }
        if (!cost_out.empty()) {
            std::printf("cost       %s\n", cost_out.c_str());
            for (const auto& f : write_cost_images(c.per_pixel, req.settings.width, req.settings.height, cost_out))
                std::printf("           %s\n", f.c_str());
        }
        if (!out.empty()) {
            r.image->write_png(out);
            std::printf("image      %s\n", out.c_str());
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "accelbench render: %s\n", e.what());
        return 2;
    }
    return 0;
}

}  // namespace accelbench
