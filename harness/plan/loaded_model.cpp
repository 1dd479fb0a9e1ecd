#include "plan/loaded_model.h"

#include <chrono>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <type_traits>

#include "accelbench/accel/registry.h"
#include "accelbench/scene/mesh_io.h"
#include "accelbench/scene/procedural.h"
#include "accelbench/verify/robustness_cases.h"
#include "models/model_registry.h"
#include "plan/derived_model.h"

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

// Raw bytes, in this machine's layout: they only cross a pipe from a child process to its
// parent, both this program.
class ByteWriter {
public:
    template <class T>
    void put(const T& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        out_.append(reinterpret_cast<const char*>(&v), sizeof v);
    }
    template <class T>
    void put_vector(const std::vector<T>& v) {
        static_assert(std::is_trivially_copyable_v<T>);
        put(uint64_t(v.size()));
        out_.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
    }
    void put_string(const std::string& s) {
        put(uint64_t(s.size()));
        out_ += s;
    }
    std::string take() { return std::move(out_); }

private:
    std::string out_;
};

// Reads what ByteWriter wrote; throws std::runtime_error naming `what` when the bytes end
// before a value does.
class ByteReader {
public:
    ByteReader(std::string_view in, const char* what) : in_(in), what_(what) {}

    template <class T>
    T take() {
        T v;
        std::memcpy(&v, next(sizeof v), sizeof v);
        return v;
    }
    template <class T>
    std::vector<T> take_vector() {
        const uint64_t n = take<uint64_t>();
        if (n > (in_.size() - at_) / sizeof(T)) truncated();
        std::vector<T> v(n);
        // An empty vector's data() may be null, and memcpy from or to null is undefined
        // even for 0 bytes (UBSan's nonnull-attribute check).
        if (n > 0) std::memcpy(v.data(), next(n * sizeof(T)), n * sizeof(T));
        return v;
    }
    std::string take_string() {
        const uint64_t n = take<uint64_t>();
        if (n > in_.size() - at_) truncated();
        return std::string(next(n), n);
    }
    bool at_end() const { return at_ == in_.size(); }

private:
    const char* next(size_t n) {
        if (n > in_.size() - at_) truncated();
        const char* p = in_.data() + at_;
        at_ += n;
        return p;
    }
    [[noreturn]] void truncated() const { throw std::runtime_error(std::string(what_) + ": truncated"); }

    std::string_view in_;
    const char* what_;
    size_t at_ = 0;
};

void put_reference(ByteWriter& w, const ReferenceAnswers& r) {
    w.put(r.seconds);
    w.put_vector(r.hits);
    w.put(uint8_t(r.image.has_value()));
    if (r.image) {
        w.put(int32_t(r.image->width));
        w.put(int32_t(r.image->height));
        w.put_vector(r.image->rgb);
    }
}

std::shared_ptr<const ReferenceAnswers> take_reference(ByteReader& r) {
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

void put_ray_set(ByteWriter& w, const GeneratedRaySet& s) {
    w.put(s.kind);
    w.put(s.query);
    w.put_vector(s.rays);
    w.put_vector(s.reference_hits);
    w.put_vector(s.reference_occluded);
    w.put_vector(s.bounce_begin);
    w.put(s.hash);
}

GeneratedRaySet take_ray_set(ByteReader& r) {
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
std::string loaded_model_bytes(const LoadedModel& m) {
    if (m.robustness_case) throw std::logic_error("a robustness case is made where it is judged, never sent");
    ByteWriter w;
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
    return w.take();
}

LoadedModel loaded_model_from_bytes(std::string_view bytes, const ModelSpec& spec) {
    ByteReader r(bytes, "prepared model");
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
        const uint64_t n = r.take<uint64_t>();
        if (n > bytes.size()) throw std::runtime_error("prepared model: truncated");
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
    if (!r.at_end()) throw std::runtime_error("prepared model: bytes after the end");
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
