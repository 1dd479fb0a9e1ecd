#include "loaded_model.h"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <stdexcept>

#include "accelbench/accel/registry.h"
#include "accelbench/scene/mesh_io.h"
#include "accelbench/scene/procedural.h"
#include "accelbench/verify/robustness_cases.h"
#include "derived_model.h"
#include "model_registry.h"

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
        case ModelSpec::Kind::Path: m.scene = load_mesh(spec.resolved_path); break;
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
    auto sets = std::make_shared<std::vector<GeneratedRaySet>>(
        make_ray_sets(*reference, model.scene, primary, model.light.position, spec.sets, spec.params));
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

template <class T>
void put(std::string& out, const T& v) {
    out.append(reinterpret_cast<const char*>(&v), sizeof v);
}

template <class T>
T take(const std::string& in, size_t& at) {
    if (at + sizeof(T) > in.size()) throw std::runtime_error("reference answers: truncated");
    T v;
    std::memcpy(&v, in.data() + at, sizeof v);
    at += sizeof v;
    return v;
}

}  // namespace

// Raw bytes, in this machine's layout: they only cross a pipe to the parent process.
std::string reference_bytes(const ReferenceAnswers& r) {
    std::string out;
    put(out, r.seconds);
    put(out, uint64_t(r.hits.size()));
    out.append(reinterpret_cast<const char*>(r.hits.data()), r.hits.size() * sizeof(Hit));
    put(out, uint8_t(r.image.has_value()));
    if (r.image) {
        put(out, int32_t(r.image->width));
        put(out, int32_t(r.image->height));
        out.append(reinterpret_cast<const char*>(r.image->rgb.data()), r.image->rgb.size());
    }
    return out;
}

std::shared_ptr<const ReferenceAnswers> reference_from_bytes(const std::string& in) {
    auto r = std::make_shared<ReferenceAnswers>();
    size_t at = 0;
    r->seconds = take<double>(in, at);
    const uint64_t n = take<uint64_t>(in, at);
    if (n > (in.size() - at) / sizeof(Hit)) throw std::runtime_error("reference answers: truncated");
    r->hits.resize(n);
    std::memcpy(r->hits.data(), in.data() + at, n * sizeof(Hit));
    at += n * sizeof(Hit);
    if (take<uint8_t>(in, at)) {
        const int32_t w = take<int32_t>(in, at), h = take<int32_t>(in, at);
        Image image(w, h);
        if (in.size() - at != image.rgb.size()) throw std::runtime_error("reference answers: truncated image");
        std::memcpy(image.rgb.data(), in.data() + at, image.rgb.size());
        r->image = std::move(image);
    }
    return r;
}

std::optional<uint64_t> known_triangles(const ModelSpec& spec, const ModelRegistry& registry) {
    // A transformed model's count is known once it is made (decimation stops near, not at,
    // its target; subdivision drops faces the half-edge mesh refuses).
    if (spec.kind != ModelSpec::Kind::Registry || spec.transform) return std::nullopt;
    const ModelEntry* entry = registry.find(spec.name);
    return entry ? std::optional<uint64_t>(entry->triangles) : std::nullopt;
}

}  // namespace accelbench
