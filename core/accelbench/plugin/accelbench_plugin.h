/* accelbench plugin interface: an acceleration structure in a shared library of its own,
 * measured by `accelbench run` beside ours and Embree (docs/adding-a-structure.md, "As a
 * plugin").
 *
 * Plain C, so that any language with a C ABI can implement it; the shape of madmann91/bvh's
 * C API (src/bvh/v2/c_api/bvh.h): opaque handles, plain structs, enums for options.
 *
 * What the boundary costs, and how it is kept small: the harness calls the plugin once per
 * BATCH of rays (a tile of the image, a chunk of a ray file: the same batches our built-in
 * structures get through accelerator.h's closest_hits/any_hits), never once per ray, and
 * there are no callbacks into the harness. The ray, hit and counter structs below have the
 * layout of the harness's own (Ray, Hit, RayStats), so a batch crosses the boundary as the
 * harness's arrays, without a copy; the vertex and index arrays of the scene likewise.
 *
 * A plugin exports one function, ACCELBENCH_PLUGIN_ENTRY_NAME, returning its description:
 * the ABI version it was compiled against (checked at load: a plugin of another version is
 * refused), its own version string (recorded in every row it measures), and one descriptor
 * per structure (name, label, description, parameter table, functions).
 *
 * Threads: create, build, build_stats and destroy are called from one thread;
 * closest_hits and any_hits may be called from several threads at once on the same built
 * structure (the render's threads share it), so they must not modify it.
 */
#ifndef ACCELBENCH_PLUGIN_H
#define ACCELBENCH_PLUGIN_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Raised whenever a struct or function below changes; a plugin reports the version it was
 * built with in accelbench_plugin.abi_version, and the harness loads only its own. */
#define ACCELBENCH_PLUGIN_ABI_VERSION 1

/* The symbol the harness looks up with dlsym. */
#define ACCELBENCH_PLUGIN_ENTRY_NAME "accelbench_plugin_entry"

/* Default visibility for the entry point, whatever -fvisibility the plugin is built with. */
#if defined(_WIN32)
#define ACCELBENCH_PLUGIN_EXPORT __declspec(dllexport)
#else
#define ACCELBENCH_PLUGIN_EXPORT __attribute__((visibility("default")))
#endif

/* "No primitive": the prim of a miss. */
#define ACCELBENCH_INVALID_PRIM 0xffffffffu
/* A build statistic the structure does not know (left missing in the CSV, never zero). */
#define ACCELBENCH_UNKNOWN_COUNT UINT64_MAX

/* A ray: origin, direction and the interval [tmin, tmax) searched. 32 bytes. */
typedef struct accelbench_ray {
    float org[3];
    float tmin;
    float dir[3];
    float tmax;
} accelbench_ray;

/* A closest hit: the triangle (index into the scene's triangles), the distance along the
 * ray and the barycentrics (p = (1-u-v) p0 + u p1 + v p2). A miss: prim =
 * ACCELBENCH_INVALID_PRIM, t = INFINITY, u = v = 0. 16 bytes. */
typedef struct accelbench_hit {
    uint32_t prim;
    float t;
    float u;
    float v;
} accelbench_hit;

/* A ray's traversal counts (the CSV's node_visits, box_tests, prim_tests), added to. */
typedef struct accelbench_ray_counters {
    uint64_t node_visits;
    uint64_t box_tests;
    uint64_t prim_tests;
} accelbench_ray_counters;

/* The scene: vertex_count vertices as x, y, z floats, triangle_count triangles as three
 * vertex indices each. Every coordinate is finite and every index in range (the harness
 * checks the scene before any structure sees it). The arrays outlive the structure built
 * over them: a structure may keep pointers to them rather than copy them. */
typedef struct accelbench_scene {
    const float* vertices;
    uint64_t vertex_count;
    const uint32_t* indices;
    uint64_t triangle_count;
} accelbench_scene;

typedef enum accelbench_param_type {
    ACCELBENCH_PARAM_INT = 0,   /* an integer in [min, max] */
    ACCELBENCH_PARAM_FLOAT = 1, /* a number in [min, max] */
    ACCELBENCH_PARAM_BOOL = 2,  /* true or false */
    ACCELBENCH_PARAM_ENUM = 3   /* one of `choices` */
} accelbench_param_type;

/* One parameter of a structure, declared as the harness declares ours: checked by the
 * harness (YAML configs, `accelbench render k=v`) before the structure sees a value, and
 * shown by `accelbench list`. default_value is text parsed like a user's value ("8",
 * "0.5", "true", "sah"); choices, for an ENUM, are the names separated by '|'. */
typedef struct accelbench_param_desc {
    const char* name;
    accelbench_param_type type;
    const char* default_value;
    double min, max;     /* INT and FLOAT, inclusive */
    const char* choices; /* ENUM: "binned|sweep"; NULL otherwise */
    const char* text;    /* what it does, one line */
} accelbench_param_desc;

/* A resolved value (the user's or the default) of the parameter at the same position of
 * the descriptor's table; the member of its type is set. enum_value is valid during the
 * call only. */
typedef struct accelbench_param_value {
    int64_t int_value;
    double float_value;
    int bool_value;
    const char* enum_value;
} accelbench_param_value;

/* After build: what the CSV's nodes, leaves, tree_depth, memory_bytes, sah_cost and
 * avg_leaf_size columns hold (ACCELBENCH_UNKNOWN_COUNT or NaN where unknown; sah_cost with
 * C_trav = C_isect = 1, as accelerator.h's kSahCostTraversal/Intersection), and extras of
 * the structure's own (the build_extra column), extra_count names and values that stay
 * valid until destroy. */
typedef struct accelbench_build_stats {
    uint64_t nodes;
    uint64_t leaves;
    uint64_t max_depth;
    uint64_t memory_bytes;
    double sah_cost;
    double avg_leaf_size;
    uint32_t extra_count;
    const char* const* extra_names;
    const double* extra_values;
} accelbench_build_stats;

/* Every figure unknown: what build_stats starts from (the harness passes it so filled). */
static inline accelbench_build_stats accelbench_unknown_build_stats(void) {
    accelbench_build_stats s = {ACCELBENCH_UNKNOWN_COUNT,
                                ACCELBENCH_UNKNOWN_COUNT,
                                ACCELBENCH_UNKNOWN_COUNT,
                                ACCELBENCH_UNKNOWN_COUNT,
                                NAN,
                                NAN,
                                0,
                                NULL,
                                NULL};
    return s;
}

/* A structure's instance, defined by the plugin. */
typedef struct accelbench_structure accelbench_structure;

/* Flags of a structure descriptor. */
enum {
    /* closest_hits and any_hits fill the counters when given some (else the count columns
     * stay missing and cost images cannot be made). */
    ACCELBENCH_COUNTS_TRAVERSAL = 1u << 0,
    /* Its ray/triangle test is watertight: no ray leaks through an edge or a vertex two
     * triangles share (robustness cases then require it). */
    ACCELBENCH_WATERTIGHT = 1u << 1
};

/* One structure of the plugin. Its name is the registry name configs use (letters,
 * digits, '_' and '-', unique among every structure the harness knows); its label the one
 * tables and figures show. Functions that can fail return NULL or non-zero and write a
 * one-line reason to error (capacity error_size, NUL-terminated). */
typedef struct accelbench_structure_desc {
    const char* name;
    const char* label;
    const char* description;
    const accelbench_param_desc* params;
    uint32_t param_count;
    uint32_t flags;

    /* An unbuilt structure with these parameters (param_count values, in table order). */
    accelbench_structure* (*create)(const accelbench_param_value* params, uint32_t param_count, char* error,
                                    size_t error_size);
    /* Builds over the scene; 0 on success. Called once. */
    int (*build)(accelbench_structure* s, const accelbench_scene* scene, char* error, size_t error_size);
    /* Closest hit of each of the count rays within [tmin, tmax): hits[i] is overwritten
     * (a miss as accelbench_hit says). counters is NULL, or count entries to add each
     * ray's counts to. A ray that is not finite, has a zero direction or a NaN bound is a
     * miss. */
    void (*closest_hits)(const accelbench_structure* s, const accelbench_ray* rays, accelbench_hit* hits,
                         uint64_t count, accelbench_ray_counters* counters);
    /* Whether anything lies within [tmin, tmax) of each ray: occluded[i] = 1 or 0. */
    void (*any_hits)(const accelbench_structure* s, const accelbench_ray* rays, uint8_t* occluded, uint64_t count,
                     accelbench_ray_counters* counters);
    /* Fills stats after a successful build. */
    void (*build_stats)(const accelbench_structure* s, accelbench_build_stats* stats);
    void (*destroy)(accelbench_structure* s);
} accelbench_structure_desc;

/* What ACCELBENCH_PLUGIN_ENTRY_NAME returns: static data that lives as long as the library. */
typedef struct accelbench_plugin {
    uint32_t abi_version; /* ACCELBENCH_PLUGIN_ABI_VERSION; first, so any version can read it */
    const char* version;  /* the plugin's own version, recorded in the CSV's plugin_version */
    const accelbench_structure_desc* structures;
    uint32_t structure_count;
} accelbench_plugin;

typedef const accelbench_plugin* (*accelbench_plugin_entry_fn)(void);

/* Declared here so that a plugin's definition is checked against it:
 *   ACCELBENCH_PLUGIN_EXPORT const accelbench_plugin* accelbench_plugin_entry(void) { ... } */
ACCELBENCH_PLUGIN_EXPORT const accelbench_plugin* accelbench_plugin_entry(void);

#ifdef __cplusplus
}
#endif

#endif /* ACCELBENCH_PLUGIN_H */
