// `accelbench list`: what a config may name — accelerators with their parameters,
// procedural scenes with theirs, and the robustness cases with their requirements;
// `--json`: the structure table the analysis reads.
#include "commands/args.h"
#include "commands/cli.h"
#include "util/text.h"

#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "accelbench/accel/registry.h"
#include "accelbench/scene/procedural.h"
#include "accelbench/verify/robustness_cases.h"

namespace accelbench {

namespace {

std::string json_params(const std::map<std::string, std::string>& given) {
    std::string out;
    for (const auto& [name, value] : given)
        out += (out.empty() ? "" : ", ") + json_quoted(name) + ": " + json_quoted(value);
    return "{" + out + "}";
}

// A declared parameter as JSON: what the text listing shows, for programs (a grid search,
// a plugin author's checks). Ranges are numbers; an enum has its choices instead.
std::string json_param_spec(const ParamSpec& p) {
    std::string domain;
    if (p.type == ParamType::Enum) {
        for (const auto& c : p.choices) domain += (domain.empty() ? "" : ", ") + json_quoted(c);
        domain = ", \"choices\": [" + domain + "]";
    } else if (p.type != ParamType::Bool) {
        char buf[96];
        std::snprintf(buf, sizeof buf, ", \"min\": %.17g, \"max\": %.17g", p.min, p.max);
        domain = buf;
    }
    return "{\"name\": " + json_quoted(p.name) + ", \"type\": \"" + to_string(p.type) +
        "\", \"default\": " + json_quoted(p.default_value) +
        ", \"scene_dependent_default\": " + (p.scene_dependent_default ? "true" : "false") + domain +
        ", \"help\": " + json_quoted(p.help) + "}";
}

// The structure table, registry order: per structure its name, label at the defaults,
// description, role, family, whether `{name: all}` leaves it out as slow, whether it
// counts its traversal, its variants (the given parameters and the label of each), its
// declared parameters, and for a plugin's structure the plugin (file, sha256, version).
void print_structure_table() {
    std::printf("{\"structures\": [");
    const char* sep = "\n";
    for (const auto& info : accelerator_registry()) {
        std::string variants, params;
        for (const auto& given : variant_settings(info))
            variants += (variants.empty() ? "" : ", ") + std::string("{\"params\": ") + json_params(given) +
                ", \"label\": " + json_quoted(info.label(resolve_params(info.name, info.params, given))) + "}";
        for (const auto& spec : info.params) params += (params.empty() ? "" : ", ") + json_param_spec(spec);
        const std::string plugin = info.plugin
            ? "{\"file\": " + json_quoted(info.plugin->file) + ", \"sha256\": " + json_quoted(info.plugin->sha256) +
                ", \"version\": " + json_quoted(info.plugin->version) + "}"
            : "null";
        std::printf(
            "%s  {\"name\": %s, \"label\": %s, \"description\": %s, \"role\": \"%s\", \"family\": %s, "
            "\"slow\": %s, \"counts_traversal\": %s, \"variants\": [%s], \"params\": [%s], \"plugin\": %s}",
            sep, json_quoted(info.name).c_str(),
            json_quoted(info.label(resolve_params(info.name, info.params, {}))).c_str(),
            json_quoted(info.description).c_str(), to_string(info.table.role), json_quoted(info.table.family).c_str(),
            info.table.slow ? "true" : "false", info.counts_traversal ? "true" : "false", variants.c_str(),
            params.c_str(), plugin.c_str());
        sep = ",\n";
    }
    std::printf("\n]}\n");
}

}  // namespace

int list_command(int argc, char** argv) {
    bool structures = false, json = false;
    std::string plugin;
    std::vector<std::string> plugins;
    Args args("list",
              "usage: accelbench list [--structures | --json] [--plugin PATH ...]\n"
              "  the accelerators with their parameters (type, default, range), the procedural scenes\n"
              "  with theirs, and the robustness cases with their requirements\n"
              "  --structures: one line per registered structure, in registry order, for scripts:\n"
              "  name, tab, label at the defaults, tab, whether it counts traversal (yes/no)\n"
              "  --json: the structure table as JSON, registry order: name, label, description, role\n"
              "  (ours, baseline, reference, plugin), family, slow (left out of {name: all}),\n"
              "  counts_traversal, the variants the report's tables show (each with its parameters and\n"
              "  label), params (name, type, default, choices or min and max, help) and plugin (file,\n"
              "  sha256, version; null for a built-in structure)\n"
              "  --plugin PATH: also the structures of this plugin (accelbench_plugin.h); repeatable\n",
              argc, argv);
    if (auto code = args.walk([&] {
            if (args.value("--plugin", plugin)) plugins.push_back(plugin);
            else if (args.flag("--structures")) structures = true;
            else if (args.flag("--json")) json = true;
            else args.unknown();
        }))
        return *code;
    if (auto code = load_plugins("list", plugins)) return *code;
    if (json) {
        print_structure_table();
        return 0;
    }
    if (structures) {
        for (const auto& info : accelerator_registry())
            std::printf("%s\t%s\t%s\n", info.name.c_str(),
                        info.label(resolve_params(info.name, info.params, {})).c_str(),
                        info.counts_traversal ? "yes" : "no");
        return 0;
    }
    auto print_params = [](const std::vector<ParamSpec>& specs) {
        for (const auto& p : specs) {
            std::string domain;
            if (p.type == ParamType::Enum) {
                for (const auto& c : p.choices) domain += (domain.empty() ? "{" : ", ") + c;
                domain += "}";
            } else if (p.type != ParamType::Bool) {
                char buf[96];
                std::snprintf(buf, sizeof buf, "[%g, %g]", p.min, p.max);
                domain = buf;
            }
            std::printf("    %-16s %-5s default %-8s %-28s %s\n", p.name.c_str(), to_string(p.type),
                        p.default_value.c_str(), domain.c_str(), p.help.c_str());
        }
    };
    std::printf("accelerators:\n");
    for (const auto& info : accelerator_registry()) {
        // The label at the defaults (the CSV's `label`; some follow the parameters).
        const ParamSet defaults = resolve_params(info.name, info.params, {});
        std::printf("  %s — %s (label: %s)\n", info.name.c_str(), info.description.c_str(),
                    info.label(defaults).c_str());
        if (info.plugin)
            std::printf("    from plugin %s, version %s\n", info.plugin->file.c_str(), info.plugin->version.c_str());
        print_params(info.params);
    }
    std::printf("\nprocedural scenes (--model procedural:KIND,k=v,...):\n");
    for (const auto& kind : procedural_registry()) {
        std::printf("  %s — %s\n", kind.name.c_str(), kind.description.c_str());
        print_params(kind.params);
    }
    // Generating a case takes microseconds to milliseconds; its requirement is part of it.
    std::printf("\nrobustness cases (configs: models: [{case: ID}] or [{case: all}]):\n");
    for (const auto& entry : robustness_case_list()) {
        const RobustnessCase c = entry.make();
        std::printf("  %-4s %s — %zu triangles, %zu rays: %s\n", c.id.c_str(), c.name.c_str(), c.scene.triangle_count(),
                    c.rays.size(), c.requirement.c_str());
    }
    return 0;
}

}  // namespace accelbench
