// Where a measurement came from: the commit, whether the tree was dirty, the compiler, build
// type and compiler flags, CPU, Embree version, the vector ISA compiled in and the one
// Embree's kernels run. Every CSV row carries these columns so results from different
// builds or machines are never silently mixed.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "accelbench/base/params.h"

namespace accelbench {

struct Provenance {
    std::string git_sha;
    bool git_dirty = false;
    std::string compiler;
    std::string build_type;
    // The compiler flags that change the code (CMakeLists.txt's ACCELBENCH_COMPILE_FLAGS:
    // CMAKE_CXX_FLAGS, the build type's flags and the options of every target, such as
    // -march), e.g. "-O3 -g -DNDEBUG -march=native -mno-avx512f -ffp-contract=off".
    std::string compile_flags;
    std::string cpu;
    std::string embree_version;
    // The vector extensions our code was compiled for (ACCELBENCH_ISA), e.g.
    // "sse2+sse4.2+avx+avx2+fma" (native on this machine) or "sse2" (portable).
    std::string isa;
    // The instruction set of the kernels Embree picks at run time on this machine
    // (EmbreeAccel::kernel_isa), e.g. "avx2" or "avx512": our side's `isa` beside Embree's.
    std::string embree_isa;
};

// Gathered once per process. git_sha and git_dirty are those of the sources compiled,
// stamped at build time (harness/scripts/provenance_stamp.cmake; "unknown" when they were
// not a git checkout): a checkout, stash, GIT_DIR or another git after the build does not
// change them.
const Provenance& provenance();

// A build's identity: the provenance columns that name the binary that measured a row
// (git_sha, git_dirty, compiler, build_type, compile_flags, isa, embree_version). The one
// list; `accelbench columns --identity` prints it.
const std::vector<std::string>& build_identity_columns();

// The one rule for mixing: rows may share a file or a median (merge, merge --take-column,
// run --resume, history, the analysis) only when these agree: the build's identity and the
// machine (cpu). Not embree_isa: that is Embree's run-time choice on this build and CPU
// (under valgrind, which a --take-column source runs under, it sees no AVX-512), nor
// render_threads and timestamp, which are per run. --allow-mixed allows it everywhere.
// `accelbench columns --mixing` prints it.
const std::vector<std::string>& mixing_columns();

// The provenance columns of every results CSV row (results.h's provenance_columns(), in
// that order) with this process's values; `threads` and `timestamp` are per run, not facts
// of the build. The rows and `accelbench provenance` both print this one list, so a driver
// that compares runs (analysis/accelbench_analysis/reproduce/runs.py) sees what rows will record.
std::vector<std::pair<std::string, std::string>> provenance_values();

// The embree_isa of one row: `shared` when the run's Embree rows all run the same kernels
// (embree_isa_of_rows), else provenance().embree_isa, except on an Embree row whose
// max_isa caps its kernels below it (EmbreeAccel::kernel_isa(max_isa)).
std::string row_embree_isa(const std::string& accel, const ParamSet& params, const std::optional<std::string>& shared);

// The kernels every Embree row of a run runs, when they share one max_isa (`max_isas`, one
// per Embree row): every row of the run is divided by those Embree rows, so every row
// records them (configs/ci.yaml caps Embree at avx2, the kernels valgrind can run, and its
// timed and callgrind runs then agree). None without Embree rows or with several caps.
std::optional<std::string> embree_isa_of_rows(const std::vector<std::string>& max_isas);

}  // namespace accelbench
