"""Provenance columns: what names the build and machine that measured a row, and where a
plugin's structure came from. Kept apart from the column table (schema.py) because the one
rule for mixing builds is read by every reader of results: history, compare, the main job's
resume."""

# A build's identity: the columns naming the binary that measured a row, as the harness's
# build_identity_columns() (harness/csv/provenance.h; `accelbench columns --identity`, which
# test_columns.py compares with this). History keeps builds apart by them: two builds
# of one commit (a Debug and a Release, two compilers, -O2 and -O3) are two series.
BUILD_IDENTITY = ["git_sha", "git_dirty", "compiler", "build_type", "compile_flags", "isa", "embree_version"]
# The one rule for mixing, as the harness's mixing_columns() (`accelbench columns --mixing`):
# rows may share a file or a median (merge, --take-column, run --resume, the main job's
# resume) only when these agree.
MIXING_COLUMNS = [*BUILD_IDENTITY, "cpu"]

# Rows differing in any of these fields were not measured with the same code on the same
# machine. `render_threads` and `timestamp` are per-run facts, not identity.
PROVENANCE_IDENTITY = [
    "git_sha",
    "git_dirty",
    "compiler",
    "build_type",
    "compile_flags",
    "cpu",
    "embree_version",
    "isa",
    "embree_isa",
]
# The vector extensions compiled in (CMake's ACCELBENCH_ISA), and the instruction set of the
# kernels Embree picked at run time (the harness's last column), and the compiler flags that
# changed the code (CMakeLists.txt's ACCELBENCH_COMPILE_FLAGS); files written before each
# existed load with "unknown": a build of its own, never mixed with a known one.
ISA_COLUMN = "isa"
EMBREE_ISA_COLUMN = "embree_isa"
COMPILE_FLAGS_COLUMN = "compile_flags"
UNKNOWN = "unknown"
# Where a structure loaded from a plugin came from (the harness's --plugin / `plugins:`):
# its shared library, the file's SHA-256 and the plugin's own version; empty for structures
# compiled in, and in files written before plugins existed.
PLUGIN_COLUMNS = ["plugin_file", "plugin_sha256", "plugin_version"]
