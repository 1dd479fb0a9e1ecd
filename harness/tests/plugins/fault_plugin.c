/* A plugin with one fault, chosen at compile time (FAULT_...), for plugin_test.cpp: the
 * loader must refuse the first four in one line naming the file, and a run must contain
 * the last three in their own rows. Without a fault it is a structure that never hits. */
#include <accelbench/plugin/accelbench_plugin.h>

#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <unistd.h>

struct accelbench_structure {
    int unused;
};

// Dies of SIGSEGV as a faulting plugin would, whatever handler the host installed (a
// sanitizer's would turn the signal into a report and an exit code).
#if defined(FAULT_CRASH_IN_BUILD) || defined(FAULT_CRASH_IN_TRACE)
static void crash(void) {
    signal(SIGSEGV, SIG_DFL);
    raise(SIGSEGV);
}
#endif

static accelbench_structure* create(const accelbench_param_value* params, uint32_t param_count, char* error,
                                    size_t error_size) {
    (void)params, (void)param_count, (void)error, (void)error_size;
    return calloc(1, sizeof(accelbench_structure));
}

static int build(accelbench_structure* s, const accelbench_scene* scene, char* error, size_t error_size) {
    (void)s, (void)scene, (void)error, (void)error_size;
#if defined(FAULT_CRASH_IN_BUILD)
    crash();
#elif defined(FAULT_HANG_IN_BUILD)
    for (;;) pause();
#endif
    return 0;
}

static void closest_hits(const accelbench_structure* s, const accelbench_ray* rays, accelbench_hit* hits,
                         uint64_t count, accelbench_ray_counters* counters) {
    (void)s, (void)rays, (void)counters;
#if defined(FAULT_CRASH_IN_TRACE)
    if (count > 0) crash();
#endif
    for (uint64_t i = 0; i < count; ++i) {
        hits[i].prim = ACCELBENCH_INVALID_PRIM;
        hits[i].t = INFINITY;
        hits[i].u = hits[i].v = 0;
    }
}

static void any_hits(const accelbench_structure* s, const accelbench_ray* rays, uint8_t* occluded, uint64_t count,
                     accelbench_ray_counters* counters) {
    (void)s, (void)rays, (void)counters;
    for (uint64_t i = 0; i < count; ++i) occluded[i] = 0;
}

static void build_stats(const accelbench_structure* s, accelbench_build_stats* stats) {
    (void)s;
    stats->nodes = 0;
}

static void destroy(accelbench_structure* s) { free(s); }

#if defined(FAULT_BAD_PARAM_TABLE)
/* A default outside its own range. */
static const accelbench_param_desc kParams[] = {
    {"leaf_size", ACCELBENCH_PARAM_INT, "100", 1, 64, NULL, "triangles per leaf"},
};
#else
static const accelbench_param_desc kParams[] = {
    {"mode", ACCELBENCH_PARAM_ENUM, "plain", 0, 0, "plain|fancy", "does nothing"},
};
#endif

#if defined(FAULT_DUPLICATE_NAME)
#define STRUCTURE_NAME "bvh" /* a built-in structure's */
#else
#define STRUCTURE_NAME FAULT_STRUCTURE_NAME
#endif

static const accelbench_structure_desc kStructures[] = {{
    STRUCTURE_NAME,
    "Fault plugin",
    "a structure that never hits, or fails as told",
    kParams,
    1,
    0,
    create,
    build,
    closest_hits,
    any_hits,
    build_stats,
    destroy,
}};

#if defined(FAULT_WRONG_ABI)
static const accelbench_plugin kPlugin = {ACCELBENCH_PLUGIN_ABI_VERSION + 1, "fault 1", kStructures, 1};
#else
static const accelbench_plugin kPlugin = {ACCELBENCH_PLUGIN_ABI_VERSION, "fault 1", kStructures, 1};
#endif

#if defined(FAULT_MISSING_SYMBOL)
/* Exported under another name than the harness looks up. */
ACCELBENCH_PLUGIN_EXPORT const accelbench_plugin* accelbench_plugin_entry_point(void) { return &kPlugin; }
#else
ACCELBENCH_PLUGIN_EXPORT const accelbench_plugin* accelbench_plugin_entry(void) { return &kPlugin; }
#endif
