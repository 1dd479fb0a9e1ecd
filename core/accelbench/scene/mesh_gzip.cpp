#include <zlib.h>

#include <fstream>

#include "accelbench/scene/mesh_reading.h"

namespace accelbench::mesh_reading {
namespace {

bool gzip_magic(std::string_view bytes, size_t at) {
    return bytes.size() - at >= 2 && uint8_t(bytes[at]) == 0x1f && uint8_t(bytes[at + 1]) == 0x8b;
}

std::string limit_text(uint64_t limit) { return limit == kMaxMeshFileBytes ? "4 GiB" : number(limit) + " bytes"; }

// Inflates the gzip members of `packed` one after the other (RFC 1952: a file of several
// members is their contents in a row). With `out` null it only counts; otherwise it
// writes the inflated bytes to out[0, size). Refuses, naming the byte and the member, data
// that is not gzip, corrupt or cut short, bytes after the last member that are not a
// member, and more than `limit` inflated bytes (as soon as they pass it).
uint64_t inflate_members(const std::string& path, std::string_view packed, uint64_t limit, char* out,
                         uint64_t out_size) {
    if (!gzip_magic(packed, 0)) fail(path, "it is named .gz but is not gzip-compressed");
    z_stream s{};
    if (inflateInit2(&s, 16 + MAX_WBITS) != Z_OK) fail(path, "gzip: cannot start zlib");
    std::vector<char> scratch(out ? 0 : 1 << 18);
    uint64_t in_pos = 0, total = 0, member = 1;
    std::string error;
    for (;;) {
        if (s.avail_in == 0 && in_pos < packed.size()) {
            const uint64_t n = std::min<uint64_t>(packed.size() - in_pos, 1u << 30);
            s.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(packed.data() + in_pos));
            s.avail_in = uInt(n);
            in_pos += n;
        }
        const uint64_t room = out ? std::min<uint64_t>(out_size - total, 1u << 30) : scratch.size();
        s.next_out = reinterpret_cast<Bytef*>(out ? out + total : scratch.data());
        s.avail_out = uInt(room);
        const int code = inflate(&s, Z_NO_FLUSH);
        total += room - s.avail_out;
        const uint64_t at = in_pos - s.avail_in;  // the first byte of `packed` not consumed
        if (total > limit) {
            error =
                "it decompresses to more than " + limit_text(limit) + ", the limit (files are read into memory whole)";
            break;
        }
        if (code == Z_STREAM_END) {
            if (at == packed.size()) break;
            if (!gzip_magic(packed, size_t(at))) {
                error = "gzip: " + number(packed.size() - at) + " bytes after the gzip data, from byte " + number(at) +
                    " (after member " + number(member) + "; not a gzip member)";
                break;
            }
            ++member;
            inflateReset(&s);
            continue;
        }
        if (code == Z_DATA_ERROR || code == Z_NEED_DICT || code == Z_STREAM_ERROR || code == Z_MEM_ERROR) {
            error = "corrupt gzip data in member " + number(member) + " near byte " + number(at) + " (" +
                (s.msg ? s.msg : "zlib error " + std::to_string(code)) + ")";
            break;
        }
        if (code == Z_BUF_ERROR && s.avail_in == 0 && in_pos == packed.size()) {
            error = "truncated gzip data: the file ends inside member " + number(member) + " (it is cut short)";
            break;
        }
        if (out && total == out_size && s.avail_out == 0 && code != Z_OK) {
            error = "gzip: the data changed between two reads";
            break;
        }
    }
    inflateEnd(&s);
    if (!error.empty()) fail(path, error);
    return total;
}

}  // namespace

std::string gunzip(const std::string& path, uint64_t limit) {
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(path, "cannot open it for reading");
    std::string packed;
    in.seekg(0, std::ios::end);
    const auto size = uint64_t(std::streamoff(in.tellg()));
    if (size > limit) fail(path, "larger than " + limit_text(limit) + ", the limit (files are read into memory whole)");
    in.seekg(0);
    packed.resize(size_t(size));
    if (!in.read(packed.data(), std::streamsize(size))) fail(path, "reading it failed");
    // Counted first, without keeping the bytes: a bomb is refused holding only the packed
    // file, and a file within the limit is inflated once more into a buffer of its size.
    const uint64_t inflated = inflate_members(path, packed, limit, nullptr, 0);
    std::string bytes(size_t(inflated), '\0');
    inflate_members(path, packed, limit, bytes.data(), inflated);
    return bytes;
}

}  // namespace accelbench::mesh_reading
