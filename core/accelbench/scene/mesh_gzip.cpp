#include "accelbench/scene/mesh_reading.h"

#include <zlib.h>

namespace accelbench::mesh_reading {

std::string gunzip(const std::string& path) {
    gzFile in = gzopen(path.c_str(), "rb");
    if (!in) fail(path, "cannot open it for reading");
    std::string bytes, error;
    std::vector<char> buffer(1 << 18);
    for (bool first = true;; first = false) {
        const int n = gzread(in, buffer.data(), unsigned(buffer.size()));
        if (first && gzdirect(in)) {
            error = "it is named .gz but is not gzip-compressed";
            break;
        }
        if (n < 0) {
            int code = 0;
            error = std::string("corrupt gzip data (") + gzerror(in, &code) + ")";
            break;
        }
        if (n == 0) break;
        if (bytes.size() + size_t(n) > kMaxMeshFileBytes) {
            error = "it decompresses to more than 4 GiB, the limit (files are read into memory whole)";
            break;
        }
        bytes.append(buffer.data(), size_t(n));
    }
    // gzclose_r reports a stream that ended in the middle (a truncated download).
    const int closed = gzclose_r(in);
    if (error.empty() && closed != Z_OK) error = "truncated or corrupt gzip data";
    if (!error.empty()) fail(path, error);
    return bytes;
}

}  // namespace accelbench::mesh_reading
