#include "plan/loaded_model.h"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "accelbench/accel/registry.h"
#include "accelbench/scene/mesh_io.h"
#include "accelbench/scene/procedural.h"
#include "accelbench/verify/robustness_cases.h"
#include "models/model_registry.h"
#include "plan/derived_model.h"
#include "util/wire.h"

namespace accelbench {

LoadedModel load_model(const ModelSpec& spec, const ModelRegistry& registry, const RenderSettings& render) {
    LoadedModel m;
    std::optional<Camera> camera = spec.camera;
    std::optional<Light> light;
    switch (spec.kind) {
        case ModelSpec::Kind::Registry: {
            const ModelEntry* entry = registry.find(spec.name);
            if (!entry) throw std::runtime_error("model '" + spec.name + "' is not in the model registry");
            m.scene =
                spec.transform ? load_derived_scene(registry, *entry, *spec.transform) : registry.load_scene(*entry);
            if (!camera) camera = entry->camera;
            light = entry->light;
            break;
        }
        case ModelSpec::Kind::Path: {
            MeshLoadInfo info;
            m.scene = load_mesh(spec.resolved_path, &info);
            if (!camera) camera = info.camera;  // a glTF's own view, when the config gives none
            break;
        }
        case ModelSpec::Kind::Case: {
            auto c = std::make_shared<const RobustnessCase>(make_robustness_case(spec.name));
            m.scene = c->scene;
            m.robustness_case = std::move(c);
            return m;  // judged with the case's own rays: no view, no light
        }
        case ModelSpec::Kind::Procedural: {
            ProceduralScene p = generate_procedural(spec.name, spec.procedural_params);
            m.scene = std::move(p.scene);
            m.albedo = std::move(p.albedo);
            if (!camera) camera = p.camera;
            light = p.light;
            break;
        }
    }
    m.camera = camera ? *camera : Camera::fit(m.scene.bounds, float(render.width) / float(render.height));
    m.light = light ? *light : default_light(m.scene.bounds, m.camera);
    m.rays = spec.rays;
    return m;
}

TraceOutput trace_model(const Accelerator& accel, const LoadedModel& model, const TraceRequest& request) {
    return model.rays ? trace_rays(accel, model.scene, model.rays->rays, request)
                      : render(accel, model.scene, model.camera, request);
}

void add_reference_answers(LoadedModel& model, const RenderSettings& render) {
    const auto t0 = std::chrono::steady_clock::now();
    auto reference = make_accelerator("reference", {});
    reference->build(model.scene);
    TraceRequest request;
    request.settings = render;
    request.settings.light = render.light && render.shading;  // shadows matter only where they are seen
    // One thread: the harness forks a measurement process per combination afterwards, and
    // the answers do not depend on the thread count.
    request.settings.threads = 1;
    request.settings.fp_mode = FpMode::Ieee;  // the ground truth of the error columns, whatever is measured
    request.light = model.light;
    request.albedo = model.albedo;
    request.keep_hits = true;
    TraceOutput out = trace_model(*reference, model, request);
    auto answers = std::make_shared<ReferenceAnswers>();
    answers->hits = std::move(out.primary_hits);
    answers->image = std::move(out.image);
    answers->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    model.reference = std::move(answers);
}

void add_ray_sets(LoadedModel& model, const RenderSettings& render, const RaySetsSpec& spec) {
    const auto t0 = std::chrono::steady_clock::now();
    auto reference = make_accelerator("reference", {});
    reference->build(model.scene);
    const std::vector<Ray> primary = camera_rays(model.camera, render);
    auto sets = std::make_shared<std::vector<GeneratedRaySet>>();
    try {
        *sets = make_ray_sets(*reference, model.scene, primary, model.light.position, spec.sets, spec.params);
    } catch (const std::exception& all) {
        // One set at a time, so that the one that fails takes only its own rows with it.
        sets->clear();
        for (RaySetKind kind : spec.sets) {
            try {
                const RaySetKind one[] = {kind};
                auto made = make_ray_sets(*reference, model.scene, primary, model.light.position, one, spec.params);
                sets->push_back(std::move(made.front()));
            } catch (const std::bad_alloc&) {
                model.ray_set_errors[kind] = "out of memory (std::bad_alloc) making it";
            } catch (const std::exception& e) {
                model.ray_set_errors[kind] = e.what();
            }
        }
        for (const auto& [kind, why] : model.ray_set_errors)
            std::fprintf(stderr, "accelbench run: ray set %s of %s cannot be made: %s\n",
                         std::string(ray_set_name(kind)).c_str(), model.scene.name.c_str(), why.c_str());
    }
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    for (const GeneratedRaySet& set : *sets)
        std::fprintf(stderr, "accelbench run: ray set %s of %s: %zu rays, hash %016llx\n",
                     std::string(ray_set_name(set.kind)).c_str(), model.scene.name.c_str(), set.rays.size(),
                     (unsigned long long)set.hash);
    std::fprintf(stderr, "accelbench run: ray sets made in %.2f s\n", s);
    model.ray_sets = std::move(sets);
}

const GeneratedRaySet& LoadedModel::ray_set(RaySetKind kind) const {
    if (ray_sets)
        for (const GeneratedRaySet& s : *ray_sets)
            if (s.kind == kind) return s;
    throw std::logic_error("ray set '" + std::string(ray_set_name(kind)) + "' was not made for this model");
}

namespace {

void put_reference(WireWriter& w, const ReferenceAnswers& r) {
    w.put(r.seconds);
    w.put_vector(r.hits);
    w.put(uint8_t(r.image.has_value()));
    if (r.image) {
        w.put(int32_t(r.image->width));
        w.put(int32_t(r.image->height));
        w.put_vector(r.image->rgb);
    }
}

std::shared_ptr<const ReferenceAnswers> take_reference(WireReader& r) {
    auto a = std::make_shared<ReferenceAnswers>();
    a->seconds = r.take<double>();
    a->hits = r.take_vector<Hit>();
    if (r.take<uint8_t>()) {
        const int32_t w = r.take<int32_t>(), h = r.take<int32_t>();
        Image image(w, h);
        auto rgb = r.take_vector<uint8_t>();
        if (rgb.size() != image.rgb.size()) throw std::runtime_error("prepared model: image of the wrong size");
        image.rgb = std::move(rgb);
        a->image = std::move(image);
    }
    return a;
}

void put_ray_set(WireWriter& w, const GeneratedRaySet& s) {
    w.put(s.kind);
    w.put(s.query);
    w.put_vector(s.rays);
    w.put_vector(s.reference_hits);
    w.put_vector(s.reference_occluded);
    w.put_vector(s.bounce_begin);
    w.put(s.hash);
}

GeneratedRaySet take_ray_set(WireReader& r) {
    GeneratedRaySet s;
    s.kind = r.take<RaySetKind>();
    s.query = r.take<RayQuery>();
    s.rays = r.take_vector<Ray>();
    s.reference_hits = r.take_vector<Hit>();
    s.reference_occluded = r.take_vector<uint8_t>();
    s.bounce_begin = r.take_vector<size_t>();
    s.hash = r.take<uint64_t>();
    return s;
}

}  // namespace

// The scene's own arrays only: the derived ones (bounds, centroids) are made again by
// finalize(), which is deterministic, so the parent's scene is the child's bit for bit.
void put_loaded_model(WireWriter& w, const LoadedModel& m) {
    if (m.robustness_case) throw std::logic_error("a robustness case is made where it is judged, never sent");
    w.put_string(m.scene.name);
    w.put_vector(m.scene.vertices);
    w.put_vector(m.scene.triangles);
    w.put(m.camera);
    w.put(m.light);
    w.put_vector(m.albedo);
    w.put(uint8_t(m.reference != nullptr));
    if (m.reference) put_reference(w, *m.reference);
    w.put(uint8_t(m.ray_sets != nullptr));
    if (m.ray_sets) {
        w.put(uint64_t(m.ray_sets->size()));
        for (const GeneratedRaySet& s : *m.ray_sets) put_ray_set(w, s);
    }
    w.put(uint64_t(m.ray_set_errors.size()));
    for (const auto& [kind, why] : m.ray_set_errors) {
        w.put(kind);
        w.put_string(why);
    }
}

LoadedModel take_loaded_model(WireReader& r, const ModelSpec& spec) {
    LoadedModel m;
    m.scene.name = r.take_string();
    m.scene.vertices = r.take_vector<Vec3>();
    m.scene.triangles = r.take_vector<std::array<uint32_t, 3>>();
    m.scene.finalize();
    m.camera = r.take<Camera>();
    m.light = r.take<Light>();
    m.albedo = r.take_vector<Vec3>();
    if (r.take<uint8_t>()) m.reference = take_reference(r);
    if (r.take<uint8_t>()) {
        // A set is its kind, query, hash and four vectors' lengths at least.
        const uint64_t n = r.take_count(sizeof(RaySetKind) + sizeof(RayQuery) + 5 * sizeof(uint64_t));
        auto sets = std::make_shared<std::vector<GeneratedRaySet>>(n);
        for (GeneratedRaySet& s : *sets) s = take_ray_set(r);
        m.ray_sets = std::move(sets);
    }
    const uint64_t errors = r.take<uint64_t>();
    if (errors > ray_set_names().size()) throw std::runtime_error("prepared model: corrupt ray set errors");
    for (uint64_t i = 0; i < errors; ++i) {
        const auto kind = r.take<RaySetKind>();
        m.ray_set_errors[kind] = r.take_string();
    }
    m.rays = spec.rays;  // the config's ray file, read by the parent when it read the config
    return m;
}

std::optional<uint64_t> known_triangles(const ModelSpec& spec, const ModelRegistry& registry) {
    // A transformed model's count is known once it is made (decimation stops near, not at,
    // its target).
    if (spec.kind != ModelSpec::Kind::Registry || spec.transform) return std::nullopt;
    const ModelEntry* entry = registry.find(spec.name);
    return entry ? std::optional<uint64_t>(entry->triangles) : std::nullopt;
}

}  // namespace accelbench
