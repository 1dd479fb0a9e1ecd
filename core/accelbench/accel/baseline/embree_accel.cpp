#include "accelbench/accel/baseline/embree_accel.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cstdio>
#include <iostream>
#include <map>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "accelbench/base/param_table.h"

namespace accelbench {

namespace {

// Embree's kernel targets from least to most capable: the values of kernel_isa() and of
// max_isa (after "auto", no cap).
constexpr std::array<std::string_view, 5> kIsaOrder = {"sse2", "sse4.2", "avx", "avx2", "avx512"};
constexpr std::array<std::string_view, 6> kMaxIsaNames = {"auto", "sse2", "sse4.2", "avx", "avx2", "avx512"};

// The parameters, each once: its row and its Config member, whose initializer is the default.
const ParamTable<EmbreeAccel::Config>& embree_params() {
    using C = EmbreeAccel::Config;
    static const ParamTable<C> rows = {
        int_param("threads", &C::threads, 0, kMaxThreads,
                  "device build threads (0 = all cores); 1 for single-thread comparisons"),
        choice_param("quality", &C::quality, std::array<std::string_view, 3>{"low", "medium", "high"},
                     std::array{RTC_BUILD_QUALITY_LOW, RTC_BUILD_QUALITY_MEDIUM, RTC_BUILD_QUALITY_HIGH},
                     "RTC_BUILD_QUALITY_*"),
        bool_param("robust", &C::robust, "RTC_SCENE_FLAG_ROBUST (watertight, slower)"),
        bool_param("compact", &C::compact, "RTC_SCENE_FLAG_COMPACT (less memory)"),
        choice_param("max_isa", &C::max_isa, kMaxIsaNames,
                     std::array<std::string, 6>{"auto", "sse2", "sse4.2", "avx", "avx2", "avx512"},
                     "the device's max_isa: the best kernels Embree may pick (auto = the best the CPU and the "
                     "library have); avx2 beside our AVX2 code, and under valgrind"),
    };
    return rows;
}

}  // namespace

AcceleratorInfo EmbreeAccel::info() {
    return {.name = "embree",
            .description = "Intel Embree 3 (rtcIntersect1/rtcOccluded1), the production baseline",
            .params = embree_params().specs(),
            .create = [](const ParamSet& p) { return std::make_unique<EmbreeAccel>(Config::from(p)); },
            .label = fixed_label("Embree"),
            // Embree's kernels keep their traversal to themselves: no per-ray counts.
            .counts_traversal = false,
            // Without RTC_SCENE_FLAG_ROBUST its triangle test may leak through shared
            // edges and vertices (Embree's documentation of the flag).
            .watertight = [](const ParamSet& p) { return Config::from(p).robust; },
            .third_party = true};
}

EmbreeAccel::Config EmbreeAccel::Config::from(const ParamSet& p) { return embree_params().from(p); }

namespace {

void error_callback(void*, RTCError code, const char* str) {
    // Embree reports errors through this callback; they become exceptions at the
    // call sites that check rtcGetDeviceError.
    (void)code;
    (void)str;
}

void check(RTCDevice device, const char* what) {
    RTCError err = rtcGetDeviceError(device);
    if (err != RTC_ERROR_NONE)
        throw std::runtime_error(std::string("embree: ") + what + " failed (error " + std::to_string(int(err)) + ")");
}

}  // namespace

EmbreeAccel::EmbreeAccel(const Config& config) : config_(config) {
    std::string device_config = "threads=" + std::to_string(config_.threads);
    if (config_.max_isa != "auto") device_config += ",max_isa=" + config_.max_isa;
    device_ = rtcNewDevice(device_config.c_str());
    if (!device_) throw std::runtime_error("embree: rtcNewDevice(\"" + device_config + "\") failed");
    rtcSetDeviceErrorFunction(device_, error_callback, nullptr);
}

EmbreeAccel::~EmbreeAccel() {
    if (scene_) rtcReleaseScene(scene_);
    if (device_) rtcReleaseDevice(device_);
}

std::string EmbreeAccel::version() {
    return std::to_string(RTC_VERSION_MAJOR) + "." + std::to_string(RTC_VERSION_MINOR) + "." +
        std::to_string(RTC_VERSION_PATCH);
}

namespace {

// Runs `f` with the process's standard output going to a temporary file, and returns what
// was written there (Embree prints its verbose report to std::cout).
template <class F>
std::string captured_stdout(F&& f) {
    std::cout.flush();
    std::fflush(stdout);
    FILE* tmp = std::tmpfile();
    const int saved = dup(STDOUT_FILENO);
    if (!tmp || saved < 0 || dup2(fileno(tmp), STDOUT_FILENO) < 0) {
        if (tmp) std::fclose(tmp);
        if (saved >= 0) close(saved);
        return "";
    }
    f();
    std::cout.flush();
    std::fflush(stdout);
    dup2(saved, STDOUT_FILENO);
    close(saved);
    std::string text;
    std::rewind(tmp);
    for (int c; (c = std::fgetc(tmp)) != EOF;) text.push_back(char(c));
    std::fclose(tmp);
    return text;
}

// The targets of the first line of `report` that contains `marker` ("SSE2 SSE4.2 AVX AVX2
// AVX512 (supported)"), each lower case.
std::vector<std::string> targets_on_line(const std::string& report, const std::string& marker) {
    std::istringstream lines(report);
    for (std::string line; std::getline(lines, line);) {
        const size_t at = line.find(marker);
        if (at == std::string::npos) continue;
        std::string list = line.substr(0, at);
        if (const size_t colon = list.find(':'); colon != std::string::npos) list = list.substr(colon + 1);
        std::istringstream words(list);
        std::vector<std::string> targets;
        for (std::string w; words >> w;) {
            for (char& c : w) c = char(std::tolower(static_cast<unsigned char>(c)));
            targets.push_back(w);
        }
        return targets;
    }
    return {};
}

}  // namespace

std::string EmbreeAccel::kernel_isa() { return kernel_isa("auto"); }

std::string EmbreeAccel::kernel_isa(const std::string& max_isa) {
    static std::mutex mutex;
    static std::map<std::string, std::string> known;  // max_isa -> the kernels
    const std::lock_guard lock(mutex);
    if (const auto it = known.find(max_isa); it != known.end()) return it->second;
    const std::string config = "verbose=1,threads=1" + (max_isa == "auto" ? "" : ",max_isa=" + max_isa);
    const std::string report = captured_stdout([&] {
        if (RTCDevice device = rtcNewDevice(config.c_str())) rtcReleaseDevice(device);
    });
    // The device section lists the targets the device enables (its CPU's, under the cap),
    // then those compiled in.
    const auto enabled = targets_on_line(report, "(supported)");
    const auto compiled = targets_on_line(report, "(compile time enabled)");
    std::string best = "unknown";
    for (std::string_view target : kIsaOrder)
        if (std::find(enabled.begin(), enabled.end(), target) != enabled.end() &&
            std::find(compiled.begin(), compiled.end(), target) != compiled.end())
            best = target;
    return known.emplace(max_isa, best).first->second;
}

void EmbreeAccel::build(const Scene& scene) {
    if (scene_) rtcReleaseScene(scene_);
    scene_ = rtcNewScene(device_);
    int flags = RTC_SCENE_FLAG_NONE;
    if (config_.robust) flags |= RTC_SCENE_FLAG_ROBUST;
    if (config_.compact) flags |= RTC_SCENE_FLAG_COMPACT;
    rtcSetSceneFlags(scene_, RTCSceneFlags(flags));
    rtcSetSceneBuildQuality(scene_, config_.quality);

    RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetGeometryBuildQuality(geom, config_.quality);
    // Embree reads vertices with 16-byte loads: the buffer gets one float of padding
    // past the last vertex (rtcSetNewGeometryBuffer allocates it so).
    auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                          3 * sizeof(float), scene.vertex_count()));
    auto* idx = static_cast<uint32_t*>(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                               3 * sizeof(uint32_t), scene.triangle_count()));
    check(device_, "allocating geometry buffers");
    for (size_t i = 0; i < scene.vertex_count(); ++i) {
        v[3 * i] = scene.vertices[i].x;
        v[3 * i + 1] = scene.vertices[i].y;
        v[3 * i + 2] = scene.vertices[i].z;
    }
    for (size_t i = 0; i < scene.triangle_count(); ++i)
        for (int k = 0; k < 3; ++k) idx[3 * i + k] = scene.triangles[i][k];
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene_, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(scene_);
    check(device_, "building the scene");
}

void EmbreeAccel::closest_hits(std::span<const Ray> rays, std::span<Hit> hits, std::span<RayStats>) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (size_t i = 0; i < rays.size(); ++i) {
        const Ray& r = rays[i];
        // Embree asserts (or, built without assertions, answers arbitrarily) on rays
        // outside its valid range: they miss, as in every other accelerator. So do rays
        // with an empty interval.
        if (!is_valid_ray(r) || !(r.tmin < r.tmax)) {
            hits[i] = Hit{};
            continue;
        }
        RTCRayHit rh;
        rh.ray.org_x = r.org.x;
        rh.ray.org_y = r.org.y;
        rh.ray.org_z = r.org.z;
        rh.ray.dir_x = r.dir.x;
        rh.ray.dir_y = r.dir.y;
        rh.ray.dir_z = r.dir.z;
        rh.ray.tnear = r.tmin;
        rh.ray.tfar = r.tmax;
        rh.ray.time = 0.0f;
        rh.ray.mask = 0xffffffffu;
        rh.ray.id = 0;
        rh.ray.flags = 0;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(scene_, &ctx, &rh);
        if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) hits[i] = Hit{rh.hit.primID, rh.ray.tfar, rh.hit.u, rh.hit.v};
        else hits[i] = Hit{};
    }
}

void EmbreeAccel::any_hits(std::span<const Ray> rays, std::span<uint8_t> occluded, std::span<RayStats>) const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (size_t i = 0; i < rays.size(); ++i) {
        const Ray& r = rays[i];
        // As above; and an input tfar of -inf would read as "occluded" below.
        if (!is_valid_ray(r) || !(r.tmin < r.tmax)) {
            occluded[i] = 0;
            continue;
        }
        RTCRay ray;
        ray.org_x = r.org.x;
        ray.org_y = r.org.y;
        ray.org_z = r.org.z;
        ray.dir_x = r.dir.x;
        ray.dir_y = r.dir.y;
        ray.dir_z = r.dir.z;
        ray.tnear = r.tmin;
        ray.tfar = r.tmax;
        ray.time = 0.0f;
        ray.mask = 0xffffffffu;
        ray.id = 0;
        ray.flags = 0;
        rtcOccluded1(scene_, &ctx, &ray);
        // Embree marks an occluded ray by setting tfar to -inf.
        occluded[i] = ray.tfar == -kInfinity ? 1 : 0;
    }
}

BuildStats EmbreeAccel::build_stats() const { return BuildStats{}; }

}  // namespace accelbench
