#include "accelbench/accel/plugin/plugin_accel.h"

#include <dlfcn.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <filesystem>
#include <set>

#include "accelbench/plugin/accelbench_plugin.h"

namespace accelbench {

// The boundary passes the harness's own arrays (no copy per batch): the C structs must be
// laid out as Ray, Hit, RayStats and the scene's vertex and index arrays are.
static_assert(sizeof(accelbench_ray) == sizeof(Ray) && offsetof(accelbench_ray, org) == offsetof(Ray, org) &&
              offsetof(accelbench_ray, tmin) == offsetof(Ray, tmin) &&
              offsetof(accelbench_ray, dir) == offsetof(Ray, dir) &&
              offsetof(accelbench_ray, tmax) == offsetof(Ray, tmax));
static_assert(sizeof(accelbench_hit) == sizeof(Hit) && offsetof(accelbench_hit, prim) == offsetof(Hit, prim) &&
              offsetof(accelbench_hit, t) == offsetof(Hit, t) && offsetof(accelbench_hit, u) == offsetof(Hit, u) &&
              offsetof(accelbench_hit, v) == offsetof(Hit, v));
static_assert(ACCELBENCH_INVALID_PRIM == kInvalidId);
static_assert(sizeof(accelbench_ray_counters) == sizeof(RayStats) &&
              offsetof(accelbench_ray_counters, node_visits) == offsetof(RayStats, node_visits) &&
              offsetof(accelbench_ray_counters, box_tests) == offsetof(RayStats, box_tests) &&
              offsetof(accelbench_ray_counters, prim_tests) == offsetof(RayStats, prim_tests));
static_assert(sizeof(Vec3) == 3 * sizeof(float) && sizeof(std::array<uint32_t, 3>) == 3 * sizeof(uint32_t));

namespace {

constexpr size_t kErrorSize = 512;

// A plugin structure: the descriptor's functions over the plugin's handle.
class PluginAccel final : public Accelerator {
public:
    PluginAccel(const accelbench_structure_desc& desc, std::string owner, accelbench_structure* handle)
        : desc_(desc), owner_(std::move(owner)), handle_(handle) {}
    ~PluginAccel() override { desc_.destroy(handle_); }
    PluginAccel(const PluginAccel&) = delete;
    PluginAccel& operator=(const PluginAccel&) = delete;

    void build(const Scene& scene) override {
        const accelbench_scene s{reinterpret_cast<const float*>(scene.vertices.data()), scene.vertices.size(),
                                 reinterpret_cast<const uint32_t*>(scene.triangles.data()), scene.triangles.size()};
        char error[kErrorSize] = {};
        if (desc_.build(handle_, &s, error, sizeof error) != 0)
            throw std::runtime_error(owner_ + ": build failed: " + std::string(error, strnlen(error, sizeof error)));
    }

    void closest_hits(std::span<const Ray> rays, std::span<Hit> hits, std::span<RayStats> stats) const override {
        desc_.closest_hits(handle_, reinterpret_cast<const accelbench_ray*>(rays.data()),
                           reinterpret_cast<accelbench_hit*>(hits.data()), rays.size(), counters(stats));
    }

    void any_hits(std::span<const Ray> rays, std::span<uint8_t> occluded, std::span<RayStats> stats) const override {
        desc_.any_hits(handle_, reinterpret_cast<const accelbench_ray*>(rays.data()), occluded.data(), rays.size(),
                       counters(stats));
    }

    BuildStats build_stats() const override {
        accelbench_build_stats s = accelbench_unknown_build_stats();
        desc_.build_stats(handle_, &s);
        auto count = [](uint64_t v) { return v == ACCELBENCH_UNKNOWN_COUNT ? std::nullopt : std::optional(v); };
        auto real = [](double v) { return std::isfinite(v) ? std::optional(v) : std::nullopt; };
        BuildStats out;
        out.nodes = count(s.nodes);
        out.leaves = count(s.leaves);
        out.max_depth = count(s.max_depth);
        out.memory_bytes = count(s.memory_bytes);
        out.sah_cost = real(s.sah_cost);
        out.avg_leaf_size = real(s.avg_leaf_size);
        for (uint32_t i = 0; i < s.extra_count && s.extra_names && s.extra_values; ++i)
            if (s.extra_names[i]) out.extra[s.extra_names[i]] = s.extra_values[i];
        return out;
    }

private:
    static accelbench_ray_counters* counters(std::span<RayStats> stats) {
        return stats.empty() ? nullptr : reinterpret_cast<accelbench_ray_counters*>(stats.data());
    }

    const accelbench_structure_desc& desc_;
    std::string owner_;
    accelbench_structure* handle_;
};

// Registry names and parameter names: letters, digits, '_' and '-' (they appear in
// configs, combination ids and the CSV's params text).
bool is_plain_name(const char* s) {
    if (!s || !*s) return false;
    for (const char* p = s; *p; ++p)
        if (!std::isalnum(static_cast<unsigned char>(*p)) && *p != '_' && *p != '-') return false;
    return true;
}

std::string quoted(const char* s) {
    if (!s) return "(null)";
    std::string q = "'";
    q.append(s).append("'");
    return q;
}

// A parameter row as the harness declares ours; throws PluginError naming what does not parse.
ParamSpec read_param(const std::string& owner, const std::string& structure, const accelbench_param_desc& d) {
    const std::string where = owner + ": structure '" + structure + "', parameter " + quoted(d.name) + ": ";
    if (!is_plain_name(d.name)) throw PluginError(where + "the name must be letters, digits, '_' or '-'");
    ParamSpec spec;
    spec.name = d.name;
    switch (d.type) {
        case ACCELBENCH_PARAM_INT: spec.type = ParamType::Int; break;
        case ACCELBENCH_PARAM_FLOAT: spec.type = ParamType::Float; break;
        case ACCELBENCH_PARAM_BOOL: spec.type = ParamType::Bool; break;
        case ACCELBENCH_PARAM_ENUM: spec.type = ParamType::Enum; break;
        default:
            throw PluginError(where + "type " + std::to_string(int(d.type)) + " is none of INT, FLOAT, BOOL, ENUM");
    }
    if (!d.default_value) throw PluginError(where + "no default value");
    if (!d.text) throw PluginError(where + "no text");
    spec.default_value = d.default_value;
    spec.help = d.text;
    if (spec.type == ParamType::Int || spec.type == ParamType::Float) {
        if (!(d.min <= d.max)) throw PluginError(where + "the range [min, max] is empty or not a number");
        spec.min = d.min;
        spec.max = d.max;
    }
    if (spec.type == ParamType::Enum) {
        if (!d.choices || !*d.choices) throw PluginError(where + "an ENUM needs choices (\"a|b|c\")");
        std::string all = d.choices;
        for (size_t at = 0;;) {
            const size_t bar = all.find('|', at);
            const std::string choice = all.substr(at, bar == std::string::npos ? std::string::npos : bar - at);
            if (!is_plain_name(choice.c_str()))
                throw PluginError(where + "choice '" + choice + "' is not a plain name");
            if (std::find(spec.choices.begin(), spec.choices.end(), choice) != spec.choices.end())
                throw PluginError(where + "choice '" + choice + "' is given twice");
            spec.choices.push_back(choice);
            if (bar == std::string::npos) break;
            at = bar + 1;
        }
    }
    try {
        parse_param(structure, spec, spec.default_value);
    } catch (const ParamError& e) {
        throw PluginError(where + "its default does not parse: " + e.what());
    }
    return spec;
}

// The parameters' resolved values, in table order, as the C side takes them.
std::vector<accelbench_param_value> param_values(const std::vector<ParamSpec>& specs, const ParamSet& set) {
    std::vector<accelbench_param_value> values(specs.size(), accelbench_param_value{0, 0.0, 0, nullptr});
    for (size_t i = 0; i < specs.size(); ++i) {
        const std::string& n = specs[i].name;
        switch (specs[i].type) {
            case ParamType::Int: values[i].int_value = set.get_int(n); break;
            case ParamType::Float: values[i].float_value = set.get_float(n); break;
            case ParamType::Bool: values[i].bool_value = set.get_bool(n) ? 1 : 0; break;
            case ParamType::Enum: values[i].enum_value = set.get_enum(n).c_str(); break;
        }
    }
    return values;
}

AcceleratorInfo read_structure(const std::string& owner, const accelbench_structure_desc& d, PluginSource source) {
    if (!is_plain_name(d.name) || std::string(d.name) == "all")
        throw PluginError(owner + ": structure name " + quoted(d.name) +
                          " must be letters, digits, '_' or '-' (and not 'all')");
    const std::string name = d.name;
    if (!d.label || !*d.label || !d.description)
        throw PluginError(owner + ": structure '" + name + "' needs a label and a description");
    if (!d.create || !d.build || !d.closest_hits || !d.any_hits || !d.build_stats || !d.destroy)
        throw PluginError(owner + ": structure '" + name + "' leaves a function of its descriptor NULL");
    if (d.param_count > 0 && !d.params)
        throw PluginError(owner + ": structure '" + name + "' declares parameters but gives no table");
    AcceleratorInfo info;
    info.name = name;
    info.description = d.description;
    std::set<std::string> seen;
    for (uint32_t i = 0; i < d.param_count; ++i) {
        info.params.push_back(read_param(owner, name, d.params[i]));
        if (!seen.insert(info.params.back().name).second)
            throw PluginError(owner + ": structure '" + name + "', parameter '" + info.params.back().name +
                              "' is declared twice");
    }
    const std::string structure_owner = owner + ": structure '" + name + "'";
    info.create = [&d, specs = info.params, structure_owner](const ParamSet& set) -> std::unique_ptr<Accelerator> {
        const auto values = param_values(specs, set);
        char error[kErrorSize] = {};
        accelbench_structure* handle = d.create(values.data(), uint32_t(values.size()), error, sizeof error);
        if (!handle)
            throw std::runtime_error(structure_owner +
                                     ": create failed: " + std::string(error, strnlen(error, sizeof error)));
        return std::make_unique<PluginAccel>(d, structure_owner, handle);
    };
    info.label = fixed_label(d.label);
    info.counts_traversal = (d.flags & ACCELBENCH_COUNTS_TRAVERSAL) != 0;
    const bool watertight = (d.flags & ACCELBENCH_WATERTIGHT) != 0;
    info.watertight = [watertight](const ParamSet&) { return watertight; };
    // Not code of this repository: a robustness failure is a finding about it, as for Embree.
    info.third_party = true;
    info.plugin = std::move(source);
    return info;
}

}  // namespace

LoadedPlugin load_plugin(const std::string& path, const std::string& sha256) {
    const std::string owner = "plugin " + path;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) throw PluginError(owner + ": no such file");
    // RTLD_LOCAL: two plugins may define the same symbols. Never closed: its structures'
    // functions are called until the process ends.
    void* library = dlopen(std::filesystem::absolute(path).c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!library) {
        const char* why = dlerror();
        throw PluginError(owner + ": not a loadable shared library (" + (why ? why : "dlopen failed") + ")");
    }
    auto entry = reinterpret_cast<accelbench_plugin_entry_fn>(dlsym(library, ACCELBENCH_PLUGIN_ENTRY_NAME));
    if (!entry)
        throw PluginError(owner +
                          ": no entry point " ACCELBENCH_PLUGIN_ENTRY_NAME
                          " (declare it with ACCELBENCH_PLUGIN_EXPORT, extern \"C\")");
    const accelbench_plugin* plugin = entry();
    if (!plugin) throw PluginError(owner + ": " ACCELBENCH_PLUGIN_ENTRY_NAME " returned NULL");
    if (plugin->abi_version != ACCELBENCH_PLUGIN_ABI_VERSION)
        throw PluginError(owner + ": built for plugin ABI version " + std::to_string(plugin->abi_version) +
                          ", this accelbench loads version " + std::to_string(ACCELBENCH_PLUGIN_ABI_VERSION) +
                          " (rebuild it against this accelbench's accelbench_plugin.h)");
    if (!plugin->version || !*plugin->version) throw PluginError(owner + ": no version string");
    if (plugin->structure_count == 0 || !plugin->structures) throw PluginError(owner + ": declares no structure");
    LoadedPlugin out{path, plugin->version, {}};
    for (uint32_t i = 0; i < plugin->structure_count; ++i) {
        AcceleratorInfo info = read_structure(owner, plugin->structures[i], PluginSource{path, sha256, out.version});
        for (const AcceleratorInfo& other : out.structures)
            if (other.name == info.name) throw PluginError(owner + ": structure '" + info.name + "' is declared twice");
        out.structures.push_back(std::move(info));
    }
    return out;
}

}  // namespace accelbench
