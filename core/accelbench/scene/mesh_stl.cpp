#include "accelbench/scene/mesh_reading.h"

#include <bit>
#include <cstring>
#include <unordered_map>

namespace accelbench::mesh_reading {

namespace {

// ---- STL (3D Systems, "StereoLithography Interface Specification", 1989) ----------------
//
// Binary: an 80-byte header, a little-endian uint32 triangle count, 50 bytes per triangle
// (normal, three corners as float32, a uint16 attribute). Chosen when the size is exactly
// 84 + 50 * count (a binary header may itself begin with "solid"). ASCII: "solid NAME",
// then per triangle "facet normal n n n / outer loop / vertex x y z (three times) /
// endloop / endfacet", then "endsolid NAME"; keywords in any case, words separated by any
// blanks or line ends, NAME the rest of its line. Several solids in a row are read as one
// mesh. STL repeats corners: equal positions become one vertex (in order of first use).
class StlVertices {
public:
    explicit StlVertices(FlatMesh& mesh) : mesh_(mesh) {}
    template <class Place>
    uint32_t index(Vec3 p, const Place& place) {
        if (!within_coordinate_limit(p)) throw MeshError(place() + vertex_problem(p));
        const auto bits = [](float c) { return std::bit_cast<uint32_t>(c == 0.0f ? 0.0f : c); };  // -0 is 0
        const Key key{bits(p.x), bits(p.y), bits(p.z)};
        const auto [it, added] = index_.try_emplace(key, uint32_t(mesh_.vertices.size()));
        if (added) mesh_.add_vertex(p, place);
        return it->second;
    }

private:
    using Key = std::array<uint32_t, 3>;
    struct Hash {
        size_t operator()(const Key& k) const {
            return size_t((uint64_t(k[0]) * 0x9E3779B97F4A7C15ull) ^ (uint64_t(k[1]) * 0xC2B2AE3D27D4EB4Full) ^
                          (uint64_t(k[2]) * 0x165667B19E3779F9ull));
        }
    };
    FlatMesh& mesh_;
    std::unordered_map<Key, uint32_t, Hash> index_;
};

void read_binary_stl(std::string_view bytes, uint64_t count, FlatMesh& mesh) {
    StlVertices vertices(mesh);
    mesh.triangles.reserve(count);
    std::vector<uint32_t> corners(3);
    for (uint64_t t = 0; t < count; ++t) {
        const size_t at = 84 + 50 * t;
        for (int c = 0; c < 3; ++c) {
            float xyz[3];
            std::memcpy(xyz, bytes.data() + at + 12 * (c + 1), 12);
            if constexpr (std::endian::native == std::endian::big)
                for (float& v : xyz) v = std::bit_cast<float>(byte_swapped(std::bit_cast<uint32_t>(v)));
            corners[size_t(c)] = vertices.index({xyz[0], xyz[1], xyz[2]}, [&] {
                return byte_at(at) + "triangle " + number(t + 1) + ", corner " + number(c + 1) + ": ";
            });
        }
        mesh.add_face(corners);
    }
}

void read_ascii_stl(std::string_view text, FlatMesh& mesh, const std::string& binary_hint) {
    Lines lines(text);
    std::vector<std::string_view> words;
    size_t w = 0;
    std::string_view line;
    bool more = true;
    // The next word, across lines; "" at the end of the file.
    const auto word = [&]() -> std::string_view {
        while (w == words.size()) {
            if (!lines.next(line)) {
                more = false;
                return {};
            }
            split_words(line, words);
            w = 0;
        }
        return words[w++];
    };
    // A solid's name is the rest of its line, up to a facet on the same line ("facet
    // normal", as one-line files write it) or, after 'endsolid', the next 'solid'.
    const auto skip_name = [&](bool after_end) {
        for (size_t k = w; k < words.size(); ++k) {
            const std::string word_k = lowercase(words[k]);
            if ((word_k == "facet" && k + 1 < words.size() && lowercase(words[k + 1]) == "normal") ||
                (after_end && k > w && word_k == "solid")) {
                w = k;
                return;
            }
        }
        w = words.size();
    };
    const auto expect = [&](const char* keyword, uint64_t triangle) {
        const std::string_view got = word();
        if (lowercase(got) == keyword) return;
        const std::string in = triangle ? "triangle " + number(triangle) + ": " : "";
        if (!more)
            throw MeshError("the file ends in " + in + "expected '" + keyword + "': it is cut short" + binary_hint);
        throw MeshError(line_at(lines.number()) + in + "expected '" + keyword + "', found " + shown(got) + binary_hint);
    };
    StlVertices vertices(mesh);
    std::vector<uint32_t> corners(3);
    uint64_t triangle = 0;
    expect("solid", 0);
    skip_name(false);
    for (;;) {
        const std::string_view got = word();
        const std::string keyword = lowercase(got);
        if (!more) throw MeshError("the file ends without 'endsolid': it is cut short");
        if (keyword == "endsolid") {
            skip_name(true);
            const std::string_view next = word();
            if (!more) return;
            if (lowercase(next) != "solid")
                throw MeshError(line_at(lines.number()) +
                                "expected 'solid' or the end of the file after 'endsolid', found " + shown(next));
            skip_name(false);
            continue;
        }
        if (keyword != "facet")
            throw MeshError(line_at(lines.number()) + "expected 'facet' or 'endsolid', found " + shown(got) +
                            binary_hint);
        ++triangle;
        expect("normal", triangle);
        for (int k = 0; k < 3; ++k) {
            float ignored;  // the normal is not used (and may be anything numeric, as writers leave it 0 or NaN)
            const std::string_view n = word();
            if (!more) throw MeshError("the file ends in triangle " + number(triangle) + "'s normal: it is cut short");
            if (parse_float(n, ignored) == Real::not_a_number)
                throw MeshError(line_at(lines.number()) + "triangle " + number(triangle) + ": normal " + shown(n) +
                                " is not a number");
        }
        expect("outer", triangle);
        expect("loop", triangle);
        for (int c = 0; c < 3; ++c) {
            expect("vertex", triangle);
            std::string_view xyz[3];
            for (auto& x : xyz) x = word();
            if (!more) throw MeshError("the file ends in triangle " + number(triangle) + ": it is cut short");
            const auto place = [&] {
                return line_at(lines.number()) + "triangle " + number(triangle) + ", corner " + number(c + 1) + ": ";
            };
            corners[size_t(c)] = vertices.index(coordinates(xyz, place), place);
        }
        expect("endloop", triangle);
        expect("endfacet", triangle);
        mesh.add_face(corners);
    }
}

}  // namespace

void read_stl(std::string_view bytes, FlatMesh& mesh) {
    uint64_t declared = 0;
    if (bytes.size() >= 84) {
        uint32_t count = 0;
        std::memcpy(&count, bytes.data() + 80, 4);
        if constexpr (std::endian::native == std::endian::big) count = byte_swapped(count);
        declared = count;
        if (84 + 50 * declared == bytes.size()) return read_binary_stl(bytes, declared, mesh);
    }
    const std::string sizes = bytes.size() >= 84 ? "declares " + number(declared) + " triangles, " +
            number(84 + 50 * declared) + " bytes, but the file has " + number(bytes.size()) + " bytes"
                                                 : "";
    // ASCII STL is text: a byte that text does not hold (a NUL, a control character) makes
    // it a binary STL of the wrong size, whatever its header begins with.
    size_t binary_byte = std::string_view::npos;
    for (size_t i = 0; i < bytes.size(); ++i) {
        const unsigned char c = static_cast<unsigned char>(bytes[i]);
        if (c < 0x20 && !std::isspace(c)) {
            binary_byte = i;
            break;
        }
    }
    const size_t first = bytes.find_first_not_of(" \t\r\n\v\f");
    const bool solid = first != std::string_view::npos && lowercase(bytes.substr(first, 5)) == "solid" &&
        (bytes.size() == first + 5 || std::isspace(static_cast<unsigned char>(bytes[first + 5])));
    if (binary_byte != std::string_view::npos || !solid) {
        if (bytes.size() < 84)
            throw MeshError(
                "corrupt STL: it does not start with 'solid' as ASCII STL does and is too short for binary "
                "STL (" +
                number(bytes.size()) + " bytes, less than the 84 of its header)");
        const std::string why = binary_byte != std::string_view::npos
            ? "byte " + number(binary_byte) + " is " + shown(bytes.substr(binary_byte, 1)) +
                ", which ASCII STL cannot hold"
            : "it does not start with 'solid' as ASCII STL does";
        const int64_t extra = int64_t(bytes.size()) - int64_t(84 + 50 * declared);
        throw MeshError("binary STL (" + why + "): its header " + sizes + ": " +
                        (extra < 0 ? "it is cut short or its count is corrupt"
                                   : "it has bytes after its triangles or its count is corrupt"));
    }
    read_ascii_stl(bytes, mesh, sizes.empty() ? "" : " (as binary STL it would " + sizes + ")");
}

}  // namespace accelbench::mesh_reading
