#include "csv/provenance.h"

#include <fstream>
#include <string>

#include "accelbench/accel/baseline/embree_accel.h"

#ifndef ACCELBENCH_BUILD_TYPE
#define ACCELBENCH_BUILD_TYPE "unknown"
#endif
#ifndef ACCELBENCH_COMPILE_FLAGS
#define ACCELBENCH_COMPILE_FLAGS "unknown"
#endif

namespace accelbench {

// The commit and dirty flag of the sources this binary was compiled from: written at build
// time into the generated provenance_stamp.cpp (harness/scripts/provenance_stamp.cmake).
extern const char* const kBuildGitSha;
extern const bool kBuildGitDirty;

namespace {

std::string cpu_model() {
    std::ifstream in("/proc/cpuinfo");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("model name", 0) == 0) {
            auto pos = line.find(':');
            return pos == std::string::npos ? line : line.substr(pos + 2);
        }
    return "unknown";
}

// The extensions the compiler was allowed to use (its predefined macros), the ones that
// matter for our code's speed; this file is compiled with the same flags as the rest.
std::string compiled_isa() {
    std::string s;
    auto add = [&s](const char* name) {
        if (!s.empty()) s += '+';
        s += name;
    };
#if defined(__SSE2__)
    add("sse2");
#endif
#if defined(__SSE4_2__)
    add("sse4.2");
#endif
#if defined(__AVX__)
    add("avx");
#endif
#if defined(__AVX2__)
    add("avx2");
#endif
#if defined(__FMA__)
    add("fma");
#endif
#if defined(__AVX512F__)
    add("avx512f");
#endif
#if defined(__ARM_NEON)
    add("neon");
#endif
    return s.empty() ? "scalar" : s;
}

}  // namespace

std::vector<std::pair<std::string, std::string>> provenance_values() {
    const Provenance& p = provenance();
    return {{"git_sha", p.git_sha},
            {"git_dirty", p.git_dirty ? "true" : "false"},
            {"compiler", p.compiler},
            {"build_type", p.build_type},
            {"compile_flags", p.compile_flags},
            {"cpu", p.cpu},
            {"embree_version", p.embree_version},
            {"isa", p.isa},
            {"embree_isa", p.embree_isa}};
}

std::string row_embree_isa(const std::string& accel, const ParamSet& params, const std::optional<std::string>& shared) {
    if (shared) return *shared;
    if (accel != EmbreeAccel::info().name) return provenance().embree_isa;
    return EmbreeAccel::kernel_isa(EmbreeAccel::Config::from(params).max_isa);
}

std::optional<std::string> embree_isa_of_rows(const std::vector<std::string>& max_isas) {
    if (max_isas.empty()) return std::nullopt;
    for (const std::string& cap : max_isas)
        if (cap != max_isas.front()) return std::nullopt;
    return EmbreeAccel::kernel_isa(max_isas.front());
}

const std::vector<std::string>& build_identity_columns() {
    static const std::vector<std::string> columns = {"git_sha",       "git_dirty", "compiler",      "build_type",
                                                     "compile_flags", "isa",       "embree_version"};
    return columns;
}

const std::vector<std::string>& mixing_columns() {
    static const std::vector<std::string> columns = [] {
        std::vector<std::string> c = build_identity_columns();
        c.push_back("cpu");
        return c;
    }();
    return columns;
}

const Provenance& provenance() {
    static const Provenance p = [] {
        Provenance p;
        p.git_sha = kBuildGitSha;
        p.git_dirty = kBuildGitDirty;
#if defined(__clang__)
        p.compiler = "clang " __clang_version__;
#elif defined(__GNUC__)
        p.compiler = "gcc " __VERSION__;
#else
        p.compiler = "unknown";
#endif
        p.build_type = ACCELBENCH_BUILD_TYPE;
        p.compile_flags = ACCELBENCH_COMPILE_FLAGS;
        p.cpu = cpu_model();
        p.embree_version = EmbreeAccel::version();
        p.isa = compiled_isa();
        p.embree_isa = EmbreeAccel::kernel_isa();
        return p;
    }();
    return p;
}

}  // namespace accelbench
