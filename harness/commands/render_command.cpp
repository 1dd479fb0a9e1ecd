// `accelbench render`: the interactive side of the harness — one model, one accelerator,
// one image, with everything it measured.
#include "commands/cli.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "accelbench/accel/registry.h"
#include "accelbench/render/renderer.h"
#include "accelbench/scene/mesh_io.h"
#include "models/model_registry.h"
#include "util/cost_image.h"

namespace accelbench {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

int usage_error(const std::string& msg) {
    std::fprintf(stderr, "accelbench render: %s\n", msg.c_str());
    std::fprintf(stderr,
                 "usage: accelbench render --model NAME|PATH|procedural:KIND[,k=v...] --accel NAME\n"
                 "         [--param k=v ...] [--out img.png] [--width W] [--height H] [--spp N]\n"
                 "         [--no-light] [--threads N] [--cost-out PREFIX]\n"
                 "--cost-out PREFIX writes PREFIX-node_visits.png, PREFIX-prim_tests.png (heatmaps, inferno,\n"
                 "each scaled to its own maximum) and PREFIX-cost.csv (per-pixel values)\n");
    return 2;
}

std::pair<std::string, std::string> split_kv(const std::string& kv) {
    auto eq = kv.find('=');
    if (eq == std::string::npos || eq == 0) throw ParamError("expected k=v, got '" + kv + "'");
    return {kv.substr(0, eq), kv.substr(eq + 1)};
}

int parse_int(const std::string& flag, const std::string& v, int lo, int hi) {
    // The one rule for how a number is written (configs and parameters alike): --width 010
    // is refused as `width: 010` is, not read as 10.
    if (const std::string why = number_form_problem(v); !why.empty()) throw ParamError(flag + ": " + why);
    try {
        size_t used = 0;
        int x = std::stoi(v, &used);
        if (used == v.size() && x >= lo && x <= hi) return x;
    } catch (const std::exception&) {}
    throw ParamError(flag + " expects an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got '" +
                     v + "'");
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
    std::string model, accel_name, out, cost_out;
    std::map<std::string, std::string> params;
    TraceRequest req;
    req.counts = CountMode::Totals;
    try {
        for (int i = 0; i < argc; ++i) {
            std::string a = argv[i];
            auto value = [&]() -> std::string {
                if (i + 1 >= argc) throw ParamError(a + " needs a value");
                return argv[++i];
            };
            if (a == "--model") model = value();
            else if (a == "--accel") accel_name = value();
            else if (a == "--param") {
                auto [k, v] = split_kv(value());
                if (!params.emplace(k, v).second) throw ParamError("--param " + k + " given twice");
            } else if (a == "--out") out = value();
            else if (a == "--cost-out") cost_out = value();
            else if (a == "--width") req.settings.width = parse_int(a, value(), 1, 16384);
            else if (a == "--height") req.settings.height = parse_int(a, value(), 1, 16384);
            else if (a == "--spp") req.settings.spp = parse_int(a, value(), 1, 4096);
            else if (a == "--threads") req.settings.threads = parse_int(a, value(), 1, 1024);
            else if (a == "--no-light") req.settings.light = false;
            else return usage_error("unknown option '" + a + "'");
        }
    } catch (const ParamError& e) {
        return usage_error(e.what());
    }
    if (model.empty() || accel_name.empty()) return usage_error("--model and --accel are required");
    const AcceleratorInfo* info = find_accelerator(accel_name);
    if (!cost_out.empty() && info && !info->counts_traversal)
        return usage_error("--cost-out needs traversal counters, which " + accel_name + " does not expose");
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
        std::printf("render     %.4f s  (%dx%d, %d spp, light %s, %d thread%s)\n", render_s, req.settings.width,
                    req.settings.height, req.settings.spp, req.settings.light ? "on" : "off", req.settings.threads,
                    req.settings.threads == 1 ? "" : "s");
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
