#include "plan/derived_model.h"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "accelbench/scene/mesh_io.h"
#include "accelbench/scene/mesh_transform.h"

namespace accelbench {

namespace fs = std::filesystem;

namespace {

// Bump when decimate() or loop_subdivide() changes what they produce: old cache files
// then no longer match and are rebuilt. 2: faces the half-edge mesh refuses are detached
// (their own corner copies) and kept, no longer dropped.
constexpr int transform_version = 2;

std::vector<std::string> cache_comments(const ModelEntry& entry, const ModelTransformSpec& t) {
    return {"accelbench derived model " + entry.name + "@" + t.text(), "source_sha256 " + entry.sha256,
            "transform_version " + std::to_string(transform_version)};
}

// Removes `path`.part<pid> files left by a process that died while writing (killed at the
// time limit, say): a part file of a live process is its writer's, left alone.
void remove_stale_parts(const std::string& path) {
    const fs::path dir = fs::path(path).parent_path();
    const std::string prefix = fs::path(path).filename().string() + ".part";
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
        const std::string name = e.path().filename().string();
        if (name.rfind(prefix, 0) != 0) continue;
        const std::string digits = name.substr(prefix.size());
        if (digits.empty() || digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 9)
            continue;
        const pid_t pid = pid_t(std::stol(digits));
        if (::kill(pid, 0) != 0 && errno == ESRCH) fs::remove(e.path(), ec);
    }
}

}  // namespace

std::string derived_model_path(const ModelRegistry& registry, const ModelEntry& entry, const ModelTransformSpec& t) {
    const std::string kind = t.kind == ModelTransformSpec::Kind::Decimate ? "decimate" : "subdivide";
    return (fs::path(registry.project_dir()) / "models" / "derived" /
            (entry.name + "-" + kind + "-" + std::to_string(t.amount) + ".ply"))
        .string();
}

Scene load_derived_scene(const ModelRegistry& registry, const ModelEntry& entry, const ModelTransformSpec& t) {
    const std::string path = derived_model_path(registry, entry, t);
    const std::vector<std::string> comments = cache_comments(entry, t);
    const std::string name = entry.name + "@" + t.text();
    if (fs::exists(path) && read_ply_comments(path) == comments) {
        Scene scene = load_mesh(path);
        scene.name = name;
        return scene;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const Scene source = registry.load_scene(entry);
    MeshTransformInfo info;
    Scene scene = t.kind == ModelTransformSpec::Kind::Decimate ? decimate(source, size_t(t.amount), &info)
                                                               : loop_subdivide(source, int(t.amount), &info);
    scene.name = name;
    fs::create_directories(fs::path(path).parent_path());
    remove_stale_parts(path);
    const std::string partial = path + ".part" + std::to_string(::getpid());
    write_ply(scene, partial, comments);
    fs::rename(partial, path);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::fprintf(stderr,
                 "accelbench: made %s: %llu -> %llu triangles, %llu vertices (of the source's faces, %llu non-manifold "
                 "and %llu with a repeated corner detached from the half-edge mesh with their own vertex copies, "
                 "none dropped) in %.1f s; cached as %s\n",
                 name.c_str(), (unsigned long long)info.source_triangles, (unsigned long long)info.triangles,
                 (unsigned long long)info.vertices, (unsigned long long)info.detached_faces,
                 (unsigned long long)info.degenerate_faces, s, path.c_str());
    return scene;
}

}  // namespace accelbench
