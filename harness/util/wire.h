// The one serialisation of everything that crosses the fork between `accelbench run` and
// its child processes (run/child_process.h): the frames on the pipe, a measurement
// (run/measure.h) and a prepared model with its reference answers and ray sets
// (plan/loaded_model.h). Values are raw bytes in this machine's layout, doubles exactly:
// both ends are this program on this machine, and a prepared model is hundreds of MB
// that must not pass through text. A reader names what it reads and throws
// std::runtime_error when the bytes end before a value does or go on after the last.
#pragma once

#include <cstdint>
#include <cstring>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace accelbench {

class WireWriter {
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
    void put_string(std::string_view s) {
        put(uint64_t(s.size()));
        out_.append(s);
    }
    template <class T>
    void put_optional(const std::optional<T>& v) {
        put(uint8_t(v.has_value()));
        if (v) put(*v);
    }
    // A map of names to strings or to trivially copyable values.
    template <class V>
    void put_map(const std::map<std::string, V>& m) {
        put(uint64_t(m.size()));
        for (const auto& [k, v] : m) {
            put_string(k);
            if constexpr (std::is_same_v<V, std::string>) put_string(v);
            else put(v);
        }
    }

    const std::string& bytes() const { return out_; }
    std::string take() { return std::move(out_); }

private:
    std::string out_;
};

class WireReader {
public:
    WireReader(std::string_view in, const char* what) : in_(in), what_(what) {}

    template <class T>
    T take() {
        static_assert(std::is_trivially_copyable_v<T>);
        T v;
        std::memcpy(&v, next(sizeof v), sizeof v);
        return v;
    }
    template <class T>
    std::vector<T> take_vector() {
        const uint64_t n = take<uint64_t>();
        if (n > left() / sizeof(T)) truncated();
        std::vector<T> v(n);
        // An empty vector's data() may be null, and memcpy from or to null is undefined
        // even for 0 bytes (UBSan's nonnull-attribute check).
        if (n > 0) std::memcpy(v.data(), next(n * sizeof(T)), n * sizeof(T));
        return v;
    }
    std::string take_string() {
        const uint64_t n = take<uint64_t>();
        if (n > left()) truncated();
        return std::string(next(n), n);
    }
    template <class T>
    std::optional<T> take_optional() {
        if (!take<uint8_t>()) return std::nullopt;
        return take<T>();
    }
    template <class V>
    std::map<std::string, V> take_map() {
        const uint64_t n = take<uint64_t>();
        if (n > left() / sizeof(uint64_t)) truncated();  // every entry has a key's length at least
        std::map<std::string, V> m;
        for (uint64_t i = 0; i < n; ++i) {
            std::string k = take_string();
            if constexpr (std::is_same_v<V, std::string>) m[std::move(k)] = take_string();
            else m[std::move(k)] = take<V>();
        }
        return m;
    }
    // A count of items that are each at least `min_bytes` long: larger than what is left
    // means damaged bytes, refused before anything is allocated for them.
    uint64_t take_count(size_t min_bytes) {
        const uint64_t n = take<uint64_t>();
        if (min_bytes > 0 && n > left() / min_bytes) truncated();
        return n;
    }

    size_t left() const { return in_.size() - at_; }
    bool at_end() const { return at_ == in_.size(); }
    // Throws when bytes are left after the last value.
    void expect_end() const {
        if (!at_end()) throw std::runtime_error(std::string(what_) + ": bytes after the end");
    }

private:
    const char* next(size_t n) {
        if (n > left()) truncated();
        const char* p = in_.data() + at_;
        at_ += n;
        return p;
    }
    [[noreturn]] void truncated() const { throw std::runtime_error(std::string(what_) + ": truncated"); }

    std::string_view in_;
    const char* what_;
    size_t at_ = 0;
};

}  // namespace accelbench
