#include "csv/provenance.h"

#include <array>
#include <cstdio>
#include <fstream>
#include <memory>
#include <string>

#include "accelbench/accel/baseline/embree_accel.h"

#ifndef ACCELBENCH_SOURCE_DIR
#define ACCELBENCH_SOURCE_DIR "."
#endif
#ifndef ACCELBENCH_BUILD_TYPE
#define ACCELBENCH_BUILD_TYPE "unknown"
#endif

namespace accelbench {

namespace {

std::string run(const std::string& cmd) {
    std::string out;
    std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(cmd.c_str(), "r"), pclose);
    if (!pipe) return out;
    std::array<char, 256> buf;
    while (fgets(buf.data(), int(buf.size()), pipe.get())) out += buf.data();
    while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
    return out;
}

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
    return {{"git_sha", p.git_sha},   {"git_dirty", p.git_dirty ? "true" : "false"},
            {"compiler", p.compiler}, {"build_type", p.build_type},
            {"cpu", p.cpu},           {"embree_version", p.embree_version},
            {"isa", p.isa},           {"embree_isa", p.embree_isa}};
}

const Provenance& provenance() {
    static const Provenance p = [] {
        Provenance p;
        const std::string git = std::string("git -C '") + ACCELBENCH_SOURCE_DIR + "' ";
        p.git_sha = run(git + "rev-parse HEAD 2>/dev/null");
        if (p.git_sha.empty()) p.git_sha = "unknown";
        // Dirty = the code differs from the commit. results/ is left out: it holds outputs
        // (a reference run rewrites results/reference/ while it measures), not code.
        p.git_dirty =
            !run(git + "status --porcelain --untracked-files=no -- . ':(exclude)results' 2>/dev/null").empty();
#if defined(__clang__)
        p.compiler = "clang " __clang_version__;
#elif defined(__GNUC__)
        p.compiler = "gcc " __VERSION__;
#else
        p.compiler = "unknown";
#endif
        p.build_type = ACCELBENCH_BUILD_TYPE;
        p.cpu = cpu_model();
        p.embree_version = EmbreeAccel::version();
        p.isa = compiled_isa();
        p.embree_isa = EmbreeAccel::kernel_isa();
        return p;
    }();
    return p;
}

}  // namespace accelbench
