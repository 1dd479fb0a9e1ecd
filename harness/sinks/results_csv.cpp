#include "sinks/results_csv.h"

#include <algorithm>
#include <map>

#include "accelbench/accel/baseline/embree_accel.h"
#include "accelbench/accel/registry.h"
#include "csv/provenance.h"
#include "plan/combinations.h"
#include "util/stats.h"
#include "util/text.h"

namespace accelbench {

namespace {

// The columns every row of a combination has, whatever its status.
Row identification_row(const Config& config, const CombinationResult& result,
                       const std::optional<std::string>& embree_isa) {
    const Combination& c = result.combination;
    const ModelSpec& model = result.model;
    Row r;
    r["config"] = config.name;
    r["combo_id"] = c.id;
    r["model"] = model.label;
    if (result.triangles) r["triangles"] = std::to_string(*result.triangles);
    if (result.vertices) r["vertices"] = std::to_string(*result.vertices);
    const bool judged = model.kind == ModelSpec::Kind::Case;  // its own rays; no image, no shadow rays
    r["ray_source"] = judged ? "robustness-case" : model.rays ? model.rays->display : "camera";
    // The workload: one of the config's ray sets, else the report's primary + shadow rays
    // timed together (`camera`, whether from the camera or a ray file: see ray_source).
    if (!judged) r["ray_set"] = c.ray_set ? std::string(ray_set_name(*c.ray_set)) : "camera";
    r["accel"] = c.accel;
    const AcceleratorInfo* info = find_accelerator(c.accel);
    if (info) r["label"] = info->label(c.params);
    r["params"] = c.params.canonical();
    // A plugin's parameters have no columns of their own (result_column_table): `params`
    // holds them, and the plugin_* columns say where the structure came from.
    if (info && info->plugin) {
        r["plugin_file"] = info->plugin->file;
        r["plugin_sha256"] = info->plugin->sha256;
        r["plugin_version"] = info->plugin->version;
    } else {
        for (const auto& [k, v] : c.params.items()) r[param_column(k)] = v;
    }
    if (!model.rays && !judged) {
        r["image_width"] = std::to_string(config.render.width);
        r["image_height"] = std::to_string(config.render.height);
        r["spp"] = std::to_string(config.render.spp);
    }
    if (!judged) {
        r["light"] = config.render.light ? "true" : "false";
        r["shading"] = config.render.shading ? "true" : "false";
    }
    // A robustness case is judged in IEEE mode whatever the config says (judge_measurement).
    r["fp_mode"] = std::string(fp_mode_name(judged ? FpMode::Ieee : config.render.fp_mode));
    for (const auto& [name, value] : provenance_values()) r[name] = value;
    r["embree_isa"] = row_embree_isa(c.accel, c.params, embree_isa);
    r["render_threads"] = std::to_string(c.threads);
    r["timestamp"] = result.timestamp;
    return r;
}

// `processes`, and with two or more the gap between the processes' medians of each time:
// largest / smallest - 1, the spread between processes that the repetitions of one process
// cannot show.
void add_process_gaps(Row& r, const Measurement& m) {
    std::map<int, std::pair<std::vector<double>, std::vector<double>>> by_process;
    for (size_t i = 0; i < m.render_s.size(); ++i) {
        auto& [build, render] = by_process[m.process.empty() ? 1 : m.process[i]];
        build.push_back(m.build_s[i]);
        render.push_back(m.render_s[i]);
    }
    r["processes"] = std::to_string(by_process.size());
    if (by_process.size() < 2) return;
    for (const bool build : {true, false}) {
        double lo = 0, hi = 0;
        for (const auto& [p, samples] : by_process) {
            const double median = summarize(build ? samples.first : samples.second).median;
            lo = lo == 0 ? median : std::min(lo, median);
            hi = std::max(hi, median);
        }
        if (lo > 0) r[build ? "build_s_process_gap" : "render_s_process_gap"] = number_text(hi / lo - 1, 6);
    }
}

void add_measurement(Row& r, const Measurement& m) {
    r["status"] = m.status;
    r["message"] = m.message;
    if (m.status != "ok") return;  // nothing that could be mistaken for a result
    for (const auto& [k, v] : m.columns) r[k] = v;
    if (m.render_s.empty()) {  // a judged robustness case: a verdict, no timing
        r["rays"] = std::to_string(m.rays);
        for (const auto& f : build_stat_fields())
            if (auto v = f.get(m.build)) r[f.name] = std::to_string(uint64_t(*v));
        return;
    }
    r["repetitions"] = std::to_string(m.render_s.size());
    for (auto [prefix, samples] :
         {std::pair<std::string, const std::vector<double>*>{"build_s", &m.build_s}, {"render_s", &m.render_s}}) {
        const Summary s = summarize(*samples);
        r[prefix + "_median"] = number_text(s.median);
        r[prefix + "_mean"] = number_text(s.mean);
        if (s.stddev) r[prefix + "_stddev"] = number_text(*s.stddev);
        if (s.ci_lo) r[prefix + "_ci_lo"] = number_text(*s.ci_lo);
        if (s.ci_hi) r[prefix + "_ci_hi"] = number_text(*s.ci_hi);
        if (s.coverage) r["ci_coverage"] = number_text(*s.coverage, 6);
    }
    add_process_gaps(r, m);
    if (!m.render_cpu_s.empty()) r["render_cpu_s_median"] = number_text(summarize(m.render_cpu_s).median);
    r["rays"] = std::to_string(m.rays);
    r["hits"] = std::to_string(m.hits);
    r["shadow_rays"] = std::to_string(m.shadow_rays);
    r["shadow_hits"] = std::to_string(m.shadow_hits);
    const uint64_t all_rays = m.rays + m.shadow_rays;
    r["mrays_per_s"] = number_text(double(all_rays) / summarize(m.render_s).median * 1e-6, 6);
    for (const auto& f : build_stat_fields())
        if (auto v = f.get(m.build)) r[f.name] = f.count ? std::to_string(*(m.build.*f.count)) : number_text(*v, 12);
    std::string extra;
    for (const auto& [k, v] : m.build.extra) append_item(extra, ";", k, "=", number_text(v));
    r["build_extra"] = extra;
    if (m.counts) {
        r["prim_tests"] = std::to_string(m.counts->prim_tests);
        r["node_visits"] = std::to_string(m.counts->node_visits);
        r["box_tests"] = std::to_string(m.counts->box_tests);
        if (all_rays) {
            r["prim_tests_per_ray"] = number_text(double(m.counts->prim_tests) / double(all_rays), 6);
            r["node_visits_per_ray"] = number_text(double(m.counts->node_visits) / double(all_rays), 6);
        }
    }
    if (m.instructions) r["instructions"] = std::to_string(*m.instructions);
}

}  // namespace

std::vector<std::string> embree_max_isas(const Config& config) {
    std::vector<std::string> caps;
    for (const Combination& c : expand(config))
        if (c.accel == EmbreeAccel::info().name) caps.push_back(EmbreeAccel::Config::from(c.params).max_isa);
    return caps;
}

Row result_row(const Config& config, const CombinationResult& result, const std::optional<std::string>& embree_isa) {
    Row r = identification_row(config, result, embree_isa);
    add_measurement(r, result.measurement);
    return r;
}

}  // namespace accelbench
