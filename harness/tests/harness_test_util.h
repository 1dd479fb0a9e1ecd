// Helpers shared by the harness tests: config files in a private temporary directory,
// the project's model registry, matching ConfigError issues, and a prepared model through
// the wire form.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "accelbench/base/temp_dir.h"
#include "config/config.h"
#include "models/model_registry.h"
#include "plan/loaded_model.h"
#include "util/wire.h"

namespace accelbench::testing_util {

inline std::string write_file(const std::filesystem::path& dir, const std::string& name, const std::string& text) {
    const std::filesystem::path p = dir / name;
    std::ofstream out(p, std::ios::binary | std::ios::trunc);
    out << text;
    return p.string();
}

inline std::string read_file(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// A prepared model in the wire form, as its child process sends it (runner.cpp), and back.
inline std::string model_wire_bytes(const LoadedModel& m) {
    WireWriter w;
    put_loaded_model(w, m);
    return w.take();
}
inline LoadedModel model_from_wire(std::string_view bytes, const ModelSpec& spec) {
    WireReader r(bytes, "prepared model");
    LoadedModel m = take_loaded_model(r, spec);
    r.expect_end();
    return m;
}

// configs/models.yaml of this source tree: the names only matter here, no mesh is read.
inline const ModelRegistry& registry() {
    static const ModelRegistry r = ModelRegistry::load_default();
    return r;
}

// One triangle in the z = 0 plane, and two rays: one through it, one beside it.
inline void write_triangle_case(const std::filesystem::path& dir) {
    write_file(dir, "tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    write_file(dir, "tri.rays.csv", "ox,oy,oz,dx,dy,dz\n0.25,0.25,1,0,0,-1\n2,2,1,0,0,-2\n0.1,0.1,-1,0,0,1\n");
}

inline std::string all_issues(const ConfigError& e) {
    std::string s;
    for (const auto& i : e.issues()) s += "  " + format_issue(i) + "\n";
    return s;
}

// The issue at line:column with this key path whose message contains `text`.
inline ::testing::AssertionResult has_issue(const ConfigError& e, int line, int column, const std::string& key_path,
                                            const std::string& text) {
    for (const auto& i : e.issues())
        if (i.mark.line == line && i.mark.column == column && i.key_path == key_path &&
            i.message.find(text) != std::string::npos)
            return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << "no issue " << line << ":" << column << " " << key_path << " '" << text
                                         << "' among:\n"
                                         << all_issues(e);
}

// Loads a config expected to be invalid and returns its error.
inline ConfigError load_error(const std::string& path) {
    try {
        load_config(path, registry());
    } catch (const ConfigError& e) {
        return e;
    }
    ADD_FAILURE() << path << " loaded without error";
    return ConfigError({});
}

}  // namespace accelbench::testing_util
