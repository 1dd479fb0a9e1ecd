#include "accelbench/scene/mesh_reading.h"

#include <bit>
#include <cstring>
#include <utility>

namespace accelbench::mesh_reading {

namespace {

// ---- PLY (Greg Turk, "The PLY Polygon File Format", 1994) -----------------------------
//
// Header: "ply", "format ascii|binary_little_endian|binary_big_endian 1.0", then
// "comment ..." / "obj_info ..." lines, "element NAME COUNT" each followed by its
// "property TYPE NAME" or "property list COUNT_TYPE ITEM_TYPE NAME" lines, and
// "end_header". Types: char uchar short ushort int uint float double and their sized
// names int8 uint8 int16 uint16 int32 uint32 float32 float64. Data: the elements in header
// order; ASCII has one element per line, every value of its type; binary is packed. We
// need element "vertex" with scalar x, y, z and element "face" with a list vertex_indices
// (or vertex_index); every other element and property is read and checked, then skipped.

enum class PlyType { i8, u8, i16, u16, i32, u32, f32, f64 };

bool ply_type(std::string_view name, PlyType& type) {
    static const std::pair<std::string_view, PlyType> names[] = {
        {"char", PlyType::i8},   {"int8", PlyType::i8},     {"uchar", PlyType::u8},   {"uint8", PlyType::u8},
        {"short", PlyType::i16}, {"int16", PlyType::i16},   {"ushort", PlyType::u16}, {"uint16", PlyType::u16},
        {"int", PlyType::i32},   {"int32", PlyType::i32},   {"uint", PlyType::u32},   {"uint32", PlyType::u32},
        {"float", PlyType::f32}, {"float32", PlyType::f32}, {"double", PlyType::f64}, {"float64", PlyType::f64}};
    for (const auto& [n, t] : names)
        if (n == name) {
            type = t;
            return true;
        }
    return false;
}
size_t ply_size(PlyType t) {
    switch (t) {
        case PlyType::i8:
        case PlyType::u8: return 1;
        case PlyType::i16:
        case PlyType::u16: return 2;
        case PlyType::i32:
        case PlyType::u32:
        case PlyType::f32: return 4;
        case PlyType::f64: return 8;
    }
    return 0;
}
bool ply_integer(PlyType t) { return t != PlyType::f32 && t != PlyType::f64; }
std::pair<int64_t, int64_t> ply_range(PlyType t) {
    switch (t) {
        case PlyType::i8: return {-128, 127};
        case PlyType::u8: return {0, 255};
        case PlyType::i16: return {-32768, 32767};
        case PlyType::u16: return {0, 65535};
        case PlyType::i32: return {INT32_MIN, INT32_MAX};
        default: return {0, UINT32_MAX};
    }
}

struct PlyProperty {
    std::string name;
    bool list = false;
    PlyType count_type = PlyType::u8;
    PlyType type = PlyType::f32;
};
struct PlyElement {
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

// One value of the data, as read: integers exactly, floats as the file's float or double.
struct PlyValue {
    int64_t integer = 0;
    double real = 0;
    float single = 0;  // for f32: the file's float bit for bit
};

// What the header declares. Binary data starts at `data`, right after "end_header" and the
// same line ending as the "ply" line's.
struct PlyHeader {
    std::string format;
    std::string_view ending;  // of the "ply" line: LF, CR LF or CR
    size_t data = 0;          // binary: the first byte after the header
    std::vector<PlyElement> elements;
};

// One "element NAME COUNT" line.
PlyElement ply_element(const std::vector<std::string_view>& words, const std::vector<PlyElement>& elements,
                       const std::string& place) {
    int64_t count = 0;
    if (words.size() != 3 || !parse_int(words[2], count) || count < 0)
        throw MeshError(place + "expected 'element NAME COUNT'");
    for (const PlyElement& e : elements)
        if (e.name == words[1]) throw MeshError(place + "a second element " + shown(words[1]));
    return {std::string(words[1]), uint64_t(count), {}};
}

// One "property TYPE NAME" or "property list COUNT_TYPE TYPE NAME" line of `element`.
PlyProperty ply_property(const std::vector<std::string_view>& words, const PlyElement& element,
                         const std::string& place) {
    PlyProperty p;
    const bool ok = words.size() >= 2 && words[1] == "list" ? words.size() == 5 && ply_type(words[2], p.count_type) &&
            ply_integer(p.count_type) && ply_type(words[3], p.type)
                                                            : words.size() == 3 && ply_type(words[1], p.type);
    if (!ok)
        throw MeshError(place +
                        "expected 'property TYPE NAME' or 'property list COUNT_TYPE TYPE NAME' "
                        "(an integer COUNT_TYPE; types: char uchar short ushort int uint float double, "
                        "or int8 ... float64)");
    p.list = words.size() == 5;
    p.name = std::string(words.back());
    for (const PlyProperty& q : element.properties)
        if (q.name == p.name) throw MeshError(place + "a second property " + shown(p.name));
    return p;
}

// One "format ascii|binary_little_endian|binary_big_endian 1.0" line.
std::string ply_format(const std::vector<std::string_view>& words, const std::string& place) {
    if (words[0] != "format" || words.size() != 3)
        throw MeshError(place + "expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
    std::string format(words[1]);
    if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian")
        throw MeshError(place + "unknown format " + shown(words[1]));
    if (words[2] != "1.0") throw MeshError(place + "unsupported PLY version " + shown(words[2]) + " (1.0 is)");
    return format;
}

// Reads the header up to and including "end_header"; `lines` is left at the first data line.
PlyHeader read_ply_header(std::string_view bytes, Lines& lines) {
    PlyHeader h;
    std::string_view line;
    lines.next(line);
    if (line != "ply") throw MeshError("not a PLY file (the first line is not 'ply')");
    h.ending = bytes.substr(3, lines.offset() - 3);
    std::vector<std::string_view> words;
    bool have_format = false;
    while (lines.next(line)) {
        const std::string place = line_at(lines.number());
        split_words(line, words);
        if (words.empty()) throw MeshError(place + "an empty header line");
        const std::string_view keyword = words[0];
        if (!have_format) {
            h.format = ply_format(words, place);
            have_format = true;
        } else if (keyword == "comment" || keyword == "obj_info") {
            continue;
        } else if (keyword == "element") {
            h.elements.push_back(ply_element(words, h.elements, place));
        } else if (keyword == "property") {
            if (h.elements.empty()) throw MeshError(place + "a property before any element");
            h.elements.back().properties.push_back(ply_property(words, h.elements.back(), place));
        } else if (keyword == "end_header") {
            if (words.size() != 1) throw MeshError(place + "'end_header' followed by more");
            if (h.format != "ascii") {
                const size_t at = size_t(line.data() - bytes.data()) + line.size();
                if (bytes.substr(at, h.ending.size()) != h.ending)
                    throw MeshError(place +
                                    "'end_header' does not end like the 'ply' line, so where the binary "
                                    "data begins is ambiguous");
                h.data = at + h.ending.size();
            }
            return h;
        } else {
            throw MeshError(place + "unknown header line " + shown(keyword));
        }
    }
    throw MeshError("corrupt PLY header (no 'end_header' line)");
}

// What the mesh needs of the data: element "vertex" with scalar x, y, z and element "face"
// with a list vertex_indices (or vertex_index). Takes each element instance as read.
class PlyMeshBuilder {
public:
    PlyMeshBuilder(const PlyHeader& header, std::string_view bytes, FlatMesh& mesh)
        : elements_(header.elements), mesh_(mesh) {
        locate_needed(bytes.size());
    }

    // Whether property p of element e holds the face's corners.
    bool face_indices(size_t e, size_t p) const { return int(p) == indices_ && int(e) == face_element_; }

    // "vertex 4" as faces refer to it (from 0), "face 5" the fifth (from 1), and so on.
    std::string instance(const PlyElement& el, uint64_t i) const {
        return el.name + " " + number(i + (&el == &elements_[size_t(vertex_element_)] ? 0 : 1));
    }
    static std::string plural(const PlyElement& el) { return el.name == "vertex" ? "vertices" : el.name + "s"; }

    // What one element instance's values mean for the mesh, once read.
    template <class Place>
    void take(size_t e, uint64_t i, const std::vector<PlyValue>& scalars, const std::vector<int64_t>& list,
              const Place& place) {
        if (int(e) == vertex_element_) {
            const PlyElement& el = elements_[e];
            float xyz[3];
            for (int k = 0; k < 3; ++k) {
                const PlyValue& v = scalars[size_t(xyz_[k])];
                const PlyType t = el.properties[size_t(xyz_[k])].type;
                if (t == PlyType::f32) xyz[k] = v.single;
                else if (t == PlyType::f64) {
                    if (std::isfinite(v.real) && !rounds_to_finite_float(v.real))
                        throw MeshError(place() + "vertex " + number(i) + ": coordinate " + std::to_string(v.real) +
                                        " is too large for a float");
                    xyz[k] = std::isfinite(v.real) ? round_to_float(v.real) : float(v.real);
                } else xyz[k] = float(v.integer);
            }
            mesh_.add_vertex({xyz[0], xyz[1], xyz[2]}, [&] { return place() + "vertex " + number(i) + ": "; });
        } else if (int(e) == face_element_) {
            const uint64_t face = i + 1;
            if (list.size() < 3) throw MeshError(place() + too_few_corners(face, list.size()));
            const uint64_t vertices = elements_[size_t(vertex_element_)].count;
            corners_.clear();
            for (int64_t v : list) {
                if (v < 0 || uint64_t(v) >= vertices)
                    throw MeshError(place() + "face " + number(face) + " refers to vertex " + std::to_string(v) +
                                    " but the file has " + number(vertices) + " vertices (PLY counts from 0)");
                corners_.push_back(uint32_t(v));
            }
            mesh_.add_face(corners_);
        }
    }

private:
    void locate_needed(size_t file_bytes) {
        for (size_t e = 0; e < elements_.size(); ++e) {
            const PlyElement& el = elements_[e];
            if (el.name == "vertex") {
                vertex_element_ = int(e);
                if (el.count > kMaxIndex) throw MeshError("the header declares more than 4294967295 vertices");
                for (int k = 0; k < 3; ++k) {
                    const char* axis[] = {"x", "y", "z"};
                    for (size_t p = 0; p < el.properties.size(); ++p)
                        if (el.properties[p].name == axis[k]) xyz_[k] = int(p);
                    if (xyz_[k] < 0 || el.properties[size_t(xyz_[k])].list)
                        throw MeshError(std::string("element vertex has no scalar property ") + axis[k]);
                }
            } else if (el.name == "face") {
                face_element_ = int(e);
                for (size_t p = 0; p < el.properties.size(); ++p) {
                    const PlyProperty& prop = el.properties[p];
                    if (prop.name != "vertex_indices" && prop.name != "vertex_index") continue;
                    if (indices_ >= 0) throw MeshError("element face has both vertex_indices and vertex_index");
                    if (!prop.list || !ply_integer(prop.type))
                        throw MeshError("face property " + prop.name + " is not a list of integers");
                    indices_ = int(p);
                }
                if (indices_ < 0) throw MeshError("element face has no list property vertex_indices");
            }
        }
        if (vertex_element_ < 0) throw MeshError("the header has no 'element vertex'");
        if (face_element_ < 0) throw MeshError("the header has no 'element face' (no triangles)");
        const uint64_t vertices = elements_[size_t(vertex_element_)].count;
        // Headers can lie (a corrupt count): reserve no more than the file could hold.
        mesh_.vertices.reserve(std::min<uint64_t>(vertices, file_bytes / 3));
        mesh_.triangles.reserve(std::min<uint64_t>(elements_[size_t(face_element_)].count, file_bytes / 4));
    }

    const std::vector<PlyElement>& elements_;
    FlatMesh& mesh_;
    int vertex_element_ = -1, face_element_ = -1, indices_ = -1;
    int xyz_[3] = {-1, -1, -1};
    std::vector<uint32_t> corners_;
};

// One ASCII value of type t; `place` says where, for the message.
template <class Place>
PlyValue ascii_value(std::string_view word, PlyType t, const Place& place) {
    PlyValue v;
    if (ply_integer(t)) {
        const auto [lo, hi] = ply_range(t);
        if (!parse_int(word, v.integer) || v.integer < lo || v.integer > hi)
            throw MeshError(place() + shown(word) + " is not a value of its integer type (" + std::to_string(lo) +
                            " to " + std::to_string(hi) + ")");
    } else if (t == PlyType::f32) {
        const Real r = parse_float(word, v.single);
        if (r == Real::not_a_number) throw MeshError(place() + shown(word) + " is not a number");
        if (r == Real::too_large) throw MeshError(place() + shown(word) + " is too large for a float");
    } else {
        const Real r = parse_double(word, v.real);
        if (r == Real::not_a_number) throw MeshError(place() + shown(word) + " is not a number");
        if (r == Real::too_large) throw MeshError(place() + shown(word) + " is too large for a double");
    }
    return v;
}

// One binary value of type t from its bytes in host order.
PlyValue binary_value(const unsigned char raw[8], PlyType t) {
    PlyValue v;
    switch (t) {
        case PlyType::i8: v.integer = int8_t(raw[0]); break;
        case PlyType::u8: v.integer = raw[0]; break;
        case PlyType::i16: {
            int16_t x;
            std::memcpy(&x, raw, 2);
            v.integer = x;
            break;
        }
        case PlyType::u16: {
            uint16_t x;
            std::memcpy(&x, raw, 2);
            v.integer = x;
            break;
        }
        case PlyType::i32: {
            int32_t x;
            std::memcpy(&x, raw, 4);
            v.integer = x;
            break;
        }
        case PlyType::u32: {
            uint32_t x;
            std::memcpy(&x, raw, 4);
            v.integer = x;
            break;
        }
        case PlyType::f32:
            std::memcpy(&v.single, raw, 4);
            v.real = v.single;
            break;
        case PlyType::f64: std::memcpy(&v.real, raw, 8); break;
    }
    return v;
}

// The ASCII data: one element instance per line, every value of its type.
void read_ply_ascii(const PlyHeader& header, Lines& lines, PlyMeshBuilder& builder) {
    const std::vector<PlyElement>& elements = header.elements;
    std::vector<std::string_view> words;
    std::vector<PlyValue> scalars;
    std::vector<int64_t> list;
    std::string_view line;
    for (size_t e = 0; e < elements.size(); ++e) {
        const PlyElement& el = elements[e];
        if (el.properties.empty()) continue;  // no values to read
        for (uint64_t i = 0; i < el.count; ++i) {
            do {
                if (!lines.next(line))
                    throw MeshError("the file ends before " + builder.instance(el, i) + " (of " + number(el.count) +
                                    " " + PlyMeshBuilder::plural(el) + " the header declares): it is cut short");
                split_words(line, words);
            } while (words.empty());
            const uint64_t line_no = lines.number();
            const auto place = [&] { return line_at(line_no); };
            scalars.assign(el.properties.size(), PlyValue{});
            list.clear();
            size_t w = 0;
            for (size_t p = 0; p < el.properties.size(); ++p) {
                const PlyProperty& prop = el.properties[p];
                const auto where = [&] { return place() + builder.instance(el, i) + ", property " + prop.name + ": "; };
                if (w >= words.size()) throw MeshError(where() + "the line ends before this property (cut short?)");
                if (!prop.list) {
                    scalars[p] = ascii_value(words[w++], prop.type, where);
                    continue;
                }
                const int64_t count = ascii_value(words[w++], prop.count_type, where).integer;
                if (count < 0) throw MeshError(where() + "a negative list length");
                if (uint64_t(count) > words.size() - w)
                    throw MeshError(where() + "the list has " + std::to_string(count) + " values but the line holds " +
                                    number(words.size() - w));
                for (int64_t k = 0; k < count; ++k) {
                    const PlyValue item = ascii_value(words[w++], prop.type, where);
                    if (builder.face_indices(e, p)) list.push_back(item.integer);
                }
            }
            if (w != words.size())
                throw MeshError(place() + builder.instance(el, i) + " has " + number(words.size() - w) +
                                " more values than its properties (one element per line)");
            builder.take(e, i, scalars, list, place);
        }
    }
    while (lines.next(line)) {
        split_words(line, words);
        if (!words.empty())
            throw MeshError(line_at(lines.number()) + "more data after the last element the header declares");
    }
}

// The binary data: the instances packed, each value in the file's byte order.
void read_ply_binary(const PlyHeader& header, std::string_view bytes, PlyMeshBuilder& builder) {
    const std::vector<PlyElement>& elements = header.elements;
    const bool swap = (header.format == "binary_big_endian") != (std::endian::native == std::endian::big);
    size_t pos = header.data;
    std::vector<PlyValue> scalars;
    std::vector<int64_t> list;
    const auto value = [&](PlyType t, const PlyElement& el, uint64_t i) {
        const size_t size = ply_size(t);
        if (bytes.size() - pos < size)
            throw MeshError(byte_at(pos) + "the file ends inside " + builder.instance(el, i) + " (of " +
                            number(el.count) + " " + PlyMeshBuilder::plural(el) +
                            " the header declares): it is cut short");
        // The value's bytes in host order (ply_size is at most 8). Copied byte by byte
        // rather than with std::reverse, which GCC 12's -march=native vectoriser warns
        // about (a -Wstringop-overflow false positive).
        unsigned char raw[8] = {};
        const auto* src = reinterpret_cast<const unsigned char*>(bytes.data() + pos);
        for (size_t k = 0; k < size && k < sizeof raw; ++k) raw[k] = swap ? src[size - 1 - k] : src[k];
        pos += size;
        return binary_value(raw, t);
    };
    for (size_t e = 0; e < elements.size(); ++e) {
        const PlyElement& el = elements[e];
        if (el.properties.empty()) continue;  // no bytes to read
        // The smallest an instance can be (lists empty): a count no file of this size holds
        // is refused before reading.
        size_t least = 0;
        for (const PlyProperty& p : el.properties) least += ply_size(p.list ? p.count_type : p.type);
        if (least > 0 && el.count > (bytes.size() - pos) / least)
            throw MeshError(byte_at(pos) + "the header declares " + number(el.count) + " " +
                            PlyMeshBuilder::plural(el) + ", at least " + number(least) + " bytes each, but only " +
                            number(bytes.size() - pos) + " bytes follow: it is cut short or its header is corrupt");
        for (uint64_t i = 0; i < el.count; ++i) {
            const size_t start = pos;
            scalars.assign(el.properties.size(), PlyValue{});
            list.clear();
            for (size_t p = 0; p < el.properties.size(); ++p) {
                const PlyProperty& prop = el.properties[p];
                if (!prop.list) {
                    scalars[p] = value(prop.type, el, i);
                    continue;
                }
                const int64_t count = value(prop.count_type, el, i).integer;
                if (count < 0)
                    throw MeshError(byte_at(start) + builder.instance(el, i) + ", property " + prop.name +
                                    ": a negative list length");
                for (int64_t k = 0; k < count; ++k) {
                    const PlyValue item = value(prop.type, el, i);
                    if (builder.face_indices(e, p)) list.push_back(item.integer);
                }
            }
            builder.take(e, i, scalars, list, [&] { return byte_at(start); });
        }
    }
    if (pos != bytes.size())
        throw MeshError(byte_at(pos) + number(bytes.size() - pos) +
                        " bytes after the last element the header declares");
}

}  // namespace

void read_ply(std::string_view bytes, FlatMesh& mesh) {
    Lines lines(bytes);
    const PlyHeader header = read_ply_header(bytes, lines);
    PlyMeshBuilder builder(header, bytes, mesh);
    if (header.format == "ascii") read_ply_ascii(header, lines, builder);
    else read_ply_binary(header, bytes, builder);
}

}  // namespace accelbench::mesh_reading
