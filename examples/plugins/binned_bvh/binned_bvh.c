/* A binary BVH built top-down with a binned SAH (Wald 2007, "On fast Construction of
 * SAH-based Bounding Volume Hierarchies"), in plain C through accelbench's plugin interface
 * (accelbench_plugin.h): the example of a structure kept in its own repository and
 * measured beside Embree and accelbench's own. The ray/triangle test is the watertight one
 * of Woop, Benthin and Wald 2013 (JCGT 2(1), "Watertight Ray/Triangle Intersection"), and
 * the box test widens its far distance by 1 + 2 gamma(3) (Ize 2013, "Robust BVH Ray
 * Traversal"), so no ray slips between two triangles or past a box it enters. */
#include <accelbench/plugin/accelbench_plugin.h>

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define STACK_SIZE 64 /* the build stops splitting at depth STACK_SIZE - 1 */
#define MAX_BINS 64

typedef struct box {
    float lo[3], hi[3];
} box;

/* count == 0: an inner node whose children are nodes first and first + 1. */
typedef struct node {
    box bounds;
    uint32_t first, count;
} node;

struct accelbench_structure {
    int64_t max_leaf_size, bins;
    const float* vertices;
    const uint32_t* indices;
    uint32_t* prims; /* triangle indices, each leaf a range of them */
    node* nodes;
    uint64_t prim_count, node_count, leaf_count, depth;
    double sah_cost; /* sum of inner areas + leaf areas x triangles, over the root's area */
};

static box empty_box(void) {
    box b = {{FLT_MAX, FLT_MAX, FLT_MAX}, {-FLT_MAX, -FLT_MAX, -FLT_MAX}};
    return b;
}

static void grow_point(box* b, const float* p) {
    for (int k = 0; k < 3; ++k) {
        b->lo[k] = fminf(b->lo[k], p[k]);
        b->hi[k] = fmaxf(b->hi[k], p[k]);
    }
}

static void grow_box(box* b, const box* o) {
    grow_point(b, o->lo);
    grow_point(b, o->hi);
}

static float half_area(const box* b) {
    const float x = b->hi[0] - b->lo[0], y = b->hi[1] - b->lo[1], z = b->hi[2] - b->lo[2];
    return x < 0 ? 0 : x * y + y * z + z * x;
}

static const float* corner(const accelbench_structure* s, uint32_t prim, int c) {
    return s->vertices + 3 * (size_t)s->indices[3 * (size_t)prim + c];
}

static box prim_box(const accelbench_structure* s, uint32_t prim) {
    box b = empty_box();
    for (int c = 0; c < 3; ++c) grow_point(&b, corner(s, prim, c));
    return b;
}

static float centroid(const accelbench_structure* s, uint32_t prim, int axis) {
    return (corner(s, prim, 0)[axis] + corner(s, prim, 1)[axis] + corner(s, prim, 2)[axis]) / 3.0f;
}

/* The bin of a centroid along `axis` of the centroid bounds [lo, lo + extent]. */
static int bin_of(float c, float lo, float extent, int bins) {
    int b = (int)((c - lo) / extent * (float)bins);
    return b < 0 ? 0 : b >= bins ? bins - 1 : b;
}

/* The best binned split of prims [first, first + count): axis and the first bin of the
 * right side; returns its SAH cost (1 + areas x counts over the node's area), or INFINITY. */
static float best_split(const accelbench_structure* s, uint32_t first, uint32_t count, const box* bounds,
                        int* best_axis, int* best_bin, float* lo_out, float* extent_out) {
    box cb = empty_box();
    for (uint32_t i = first; i < first + count; ++i) {
        float c[3];
        for (int k = 0; k < 3; ++k) c[k] = centroid(s, s->prims[i], k);
        grow_point(&cb, c);
    }
    float best = INFINITY;
    const int bins = (int)s->bins;
    for (int axis = 0; axis < 3; ++axis) {
        const float lo = cb.lo[axis], extent = cb.hi[axis] - cb.lo[axis];
        if (!(extent > 0)) continue;
        box bin_box[MAX_BINS];
        uint32_t bin_count[MAX_BINS] = {0};
        for (int b = 0; b < bins; ++b) bin_box[b] = empty_box();
        for (uint32_t i = first; i < first + count; ++i) {
            const int b = bin_of(centroid(s, s->prims[i], axis), lo, extent, bins);
            const box pb = prim_box(s, s->prims[i]);
            grow_box(&bin_box[b], &pb);
            ++bin_count[b];
        }
        float right_area[MAX_BINS];
        uint32_t right_count[MAX_BINS];
        box acc = empty_box();
        uint32_t n = 0;
        for (int b = bins - 1; b > 0; --b) {
            grow_box(&acc, &bin_box[b]);
            n += bin_count[b];
            right_area[b] = half_area(&acc);
            right_count[b] = n;
        }
        acc = empty_box();
        n = 0;
        for (int b = 1; b < bins; ++b) {
            grow_box(&acc, &bin_box[b - 1]);
            n += bin_count[b - 1];
            if (n == 0 || right_count[b] == 0) continue;
            const float cost =
                1.0f + (half_area(&acc) * (float)n + right_area[b] * (float)right_count[b]) / half_area(bounds);
            if (cost < best) {
                best = cost;
                *best_axis = axis;
                *best_bin = b;
                *lo_out = lo;
                *extent_out = extent;
            }
        }
    }
    return best;
}

static void build_node(accelbench_structure* s, uint32_t index, uint32_t first, uint32_t count, uint64_t depth,
                       float root_area) {
    node* n = &s->nodes[index];
    n->bounds = empty_box();
    for (uint32_t i = first; i < first + count; ++i) {
        const box pb = prim_box(s, s->prims[i]);
        grow_box(&n->bounds, &pb);
    }
    if (depth > s->depth) s->depth = depth;
    const float area = root_area > 0 ? half_area(&n->bounds) / root_area : 1.0f;
    /* A leaf when small enough, at the depth limit, or when the best split costs more than
     * testing every triangle; a node whose centroids all coincide (no split by bins) is
     * halved as long as it is over max_leaf_size. */
    int axis = 0, bin = -1;
    float lo = 0, extent = 0;
    int leaf = count <= (uint32_t)s->max_leaf_size || depth + 1 >= STACK_SIZE;
    if (!leaf) {
        const float split_cost = best_split(s, first, count, &n->bounds, &axis, &bin, &lo, &extent);
        if (split_cost < INFINITY && split_cost >= (float)count) leaf = 1;
        if (!(split_cost < INFINITY)) bin = -1;
    }
    if (leaf) {
        n->first = first;
        n->count = count;
        ++s->leaf_count;
        s->sah_cost += (double)area * count;
        return;
    }
    uint32_t mid = first + count / 2;
    if (bin >= 0) {
        mid = first;
        for (uint32_t i = first; i < first + count; ++i)
            if (bin_of(centroid(s, s->prims[i], axis), lo, extent, (int)s->bins) < bin) {
                const uint32_t t = s->prims[i];
                s->prims[i] = s->prims[mid];
                s->prims[mid++] = t;
            }
    }
    s->sah_cost += area;
    const uint32_t left = (uint32_t)s->node_count;
    s->node_count += 2;
    n->first = left;
    n->count = 0;
    build_node(s, left, first, mid - first, depth + 1, root_area);
    build_node(s, left + 1, mid, first + count - mid, depth + 1, root_area);
}

static accelbench_structure* create(const accelbench_param_value* params, uint32_t param_count, char* error,
                                    size_t error_size) {
    if (param_count != 2) {
        snprintf(error, error_size, "expected 2 parameters, got %u", param_count);
        return NULL;
    }
    accelbench_structure* s = calloc(1, sizeof *s);
    if (!s) {
        snprintf(error, error_size, "out of memory");
        return NULL;
    }
    s->max_leaf_size = params[0].int_value;
    s->bins = params[1].int_value;
    return s;
}

static int build(accelbench_structure* s, const accelbench_scene* scene, char* error, size_t error_size) {
    const uint64_t n = scene->triangle_count;
    if (n >= UINT32_MAX / 2) {
        snprintf(error, error_size, "%llu triangles: at most %u", (unsigned long long)n, UINT32_MAX / 2 - 1);
        return 1;
    }
    s->vertices = scene->vertices;
    s->indices = scene->indices;
    s->prims = malloc((n ? n : 1) * sizeof *s->prims);
    s->nodes = malloc((2 * n + 1) * sizeof *s->nodes);
    if (!s->prims || !s->nodes) {
        snprintf(error, error_size, "out of memory for %llu triangles", (unsigned long long)n);
        return 1;
    }
    for (uint32_t i = 0; i < n; ++i) s->prims[i] = i;
    s->prim_count = n;
    s->node_count = 1;
    box root = empty_box();
    for (uint32_t i = 0; i < n; ++i) {
        const box pb = prim_box(s, i);
        grow_box(&root, &pb);
    }
    build_node(s, 0, 0, (uint32_t)n, 0, half_area(&root));
    return 0;
}

/* ---- traversal ---------------------------------------------------------------------- */

typedef struct prepared_ray {
    float org[3], inv[3];
    int kx, ky, kz; /* the watertight test's axes: kz the largest direction component */
    float sx, sy, sz;
} prepared_ray;

static int valid_ray(const accelbench_ray* r) {
    for (int k = 0; k < 3; ++k)
        if (!isfinite(r->org[k]) || !isfinite(r->dir[k])) return 0;
    return (r->dir[0] != 0 || r->dir[1] != 0 || r->dir[2] != 0) && !isnan(r->tmin) && !isnan(r->tmax);
}

static prepared_ray prepare(const accelbench_ray* r) {
    prepared_ray p;
    int kz = 0;
    for (int k = 0; k < 3; ++k) {
        p.org[k] = r->org[k];
        p.inv[k] = 1.0f / r->dir[k];
        if (fabsf(r->dir[k]) > fabsf(r->dir[kz])) kz = k;
    }
    p.kz = kz;
    p.kx = (kz + 1) % 3;
    p.ky = (p.kx + 1) % 3;
    if (r->dir[kz] < 0) {
        const int t = p.kx;
        p.kx = p.ky;
        p.ky = t;
    }
    p.sx = r->dir[p.kx] / r->dir[kz];
    p.sy = r->dir[p.ky] / r->dir[kz];
    p.sz = 1.0f / r->dir[kz];
    return p;
}

/* The entry distance of the box within [tmin, tmax), or INFINITY when the ray misses it. */
static float enter_box(const prepared_ray* p, const box* b, float tmin, float tmax) {
    const float widen = 1.0f + 2.0f * (3.0f * FLT_EPSILON * 0.5f) / (1.0f - 3.0f * FLT_EPSILON * 0.5f);
    float t0 = tmin, t1 = tmax;
    for (int k = 0; k < 3; ++k) {
        float a = (b->lo[k] - p->org[k]) * p->inv[k], c = (b->hi[k] - p->org[k]) * p->inv[k];
        if (a > c) {
            const float t = a;
            a = c;
            c = t;
        }
        t0 = fmaxf(t0, a); /* fmaxf/fminf drop a NaN (0 x inf): that axis does not bound */
        t1 = fminf(t1, c * widen);
    }
    return t0 <= t1 ? t0 : INFINITY;
}

/* Woop et al. 2013: 1 and hit filled when the triangle is hit within [tmin, tmax). */
static int hit_triangle(const accelbench_structure* s, const prepared_ray* p, uint32_t prim, float tmin, float tmax,
                        accelbench_hit* hit) {
    float a[3], b[3], c[3];
    for (int k = 0; k < 3; ++k) {
        a[k] = corner(s, prim, 0)[k] - p->org[k];
        b[k] = corner(s, prim, 1)[k] - p->org[k];
        c[k] = corner(s, prim, 2)[k] - p->org[k];
    }
    const float ax = a[p->kx] - p->sx * a[p->kz], ay = a[p->ky] - p->sy * a[p->kz];
    const float bx = b[p->kx] - p->sx * b[p->kz], by = b[p->ky] - p->sy * b[p->kz];
    const float cx = c[p->kx] - p->sx * c[p->kz], cy = c[p->ky] - p->sy * c[p->kz];
    float u = cx * by - cy * bx, v = ax * cy - ay * cx, w = bx * ay - by * ax;
    if (u == 0 || v == 0 || w == 0) { /* on an edge in float: decide in double */
        u = (float)((double)cx * by - (double)cy * bx);
        v = (float)((double)ax * cy - (double)ay * cx);
        w = (float)((double)bx * ay - (double)by * ax);
    }
    if ((u < 0 || v < 0 || w < 0) && (u > 0 || v > 0 || w > 0)) return 0;
    const float det = u + v + w;
    if (det == 0) return 0;
    const float t = (u * (p->sz * a[p->kz]) + v * (p->sz * b[p->kz]) + w * (p->sz * c[p->kz])) / det;
    if (!(t >= tmin && t < tmax)) return 0;
    hit->prim = prim;
    hit->t = t;
    hit->u = v / det;
    hit->v = w / det;
    return 1;
}

/* Closest hit (any_hit = 0) or the first hit found (any_hit = 1) of one ray. */
static int trace(const accelbench_structure* s, const accelbench_ray* r, int any_hit, accelbench_hit* hit,
                 accelbench_ray_counters* counters) {
    hit->prim = ACCELBENCH_INVALID_PRIM;
    hit->t = INFINITY;
    hit->u = hit->v = 0;
    if (!valid_ray(r) || s->node_count == 0 || s->leaf_count == 0) return 0;
    const prepared_ray p = prepare(r);
    float tmax = r->tmax;
    uint32_t stack[STACK_SIZE];
    int top = 0;
    if (enter_box(&p, &s->nodes[0].bounds, r->tmin, tmax) == INFINITY) return 0;
    stack[top++] = 0;
    if (counters) counters->box_tests += 1;
    while (top > 0) {
        const node* n = &s->nodes[stack[--top]];
        if (counters) counters->node_visits += 1;
        if (n->count > 0) {
            for (uint32_t i = n->first; i < n->first + n->count; ++i) {
                if (counters) counters->prim_tests += 1;
                if (hit_triangle(s, &p, s->prims[i], r->tmin, tmax, hit)) {
                    if (any_hit) return 1;
                    tmax = hit->t;
                }
            }
            continue;
        }
        const float tl = enter_box(&p, &s->nodes[n->first].bounds, r->tmin, tmax);
        const float tr = enter_box(&p, &s->nodes[n->first + 1].bounds, r->tmin, tmax);
        if (counters) counters->box_tests += 2;
        /* The nearer child is popped first. */
        if (tl <= tr) {
            if (tr != INFINITY) stack[top++] = n->first + 1;
            if (tl != INFINITY) stack[top++] = n->first;
        } else {
            if (tl != INFINITY) stack[top++] = n->first;
            stack[top++] = n->first + 1;
        }
    }
    return hit->prim != ACCELBENCH_INVALID_PRIM;
}

static void closest_hits(const accelbench_structure* s, const accelbench_ray* rays, accelbench_hit* hits,
                         uint64_t count, accelbench_ray_counters* counters) {
    for (uint64_t i = 0; i < count; ++i) trace(s, &rays[i], 0, &hits[i], counters ? &counters[i] : NULL);
}

static void any_hits(const accelbench_structure* s, const accelbench_ray* rays, uint8_t* occluded, uint64_t count,
                     accelbench_ray_counters* counters) {
    for (uint64_t i = 0; i < count; ++i) {
        accelbench_hit hit;
        occluded[i] = (uint8_t)trace(s, &rays[i], 1, &hit, counters ? &counters[i] : NULL);
    }
}

static void build_stats(const accelbench_structure* s, accelbench_build_stats* stats) {
    stats->nodes = s->node_count;
    stats->leaves = s->leaf_count;
    stats->max_depth = s->depth;
    stats->memory_bytes = s->node_count * sizeof(node) + s->prim_count * sizeof(uint32_t);
    stats->sah_cost = s->sah_cost;
    stats->avg_leaf_size = s->leaf_count ? (double)s->prim_count / (double)s->leaf_count : NAN;
}

static void destroy(accelbench_structure* s) {
    if (!s) return;
    free(s->prims);
    free(s->nodes);
    free(s);
}

static const accelbench_param_desc kParams[] = {
    {"max_leaf_size", ACCELBENCH_PARAM_INT, "4", 1, 64, NULL, "a node of this many triangles or fewer is a leaf"},
    {"bins", ACCELBENCH_PARAM_INT, "16", 2, MAX_BINS, NULL, "SAH bins per axis"},
};

static const accelbench_structure_desc kStructures[] = {{
    "example_bvh",
    "Example BVH (plugin)",
    "binary BVH, binned SAH, watertight triangle test: the out-of-tree plugin example",
    kParams,
    2,
    ACCELBENCH_COUNTS_TRAVERSAL | ACCELBENCH_WATERTIGHT,
    create,
    build,
    closest_hits,
    any_hits,
    build_stats,
    destroy,
}};

static const accelbench_plugin kPlugin = {ACCELBENCH_PLUGIN_ABI_VERSION, "example_bvh 1.0", kStructures, 1};

ACCELBENCH_PLUGIN_EXPORT const accelbench_plugin* accelbench_plugin_entry(void) { return &kPlugin; }
