// SHA-256 (FIPS 180-4), to check model files against the registry's checksums without
// depending on an external tool. The hashing is OpenSSL's libcrypto (EVP digest API);
// this wraps it in the small interface the registry and the tests use.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>

struct evp_md_ctx_st;  // OpenSSL's EVP_MD_CTX, kept out of this header

namespace accelbench {

class Sha256 {
public:
    Sha256();
    void update(const void* data, size_t size);
    void update(std::string_view bytes) { update(bytes.data(), bytes.size()); }
    // The digest as 64 lowercase hex digits. Finishes the hash: call once.
    std::string hex_digest();

private:
    struct FreeContext {
        void operator()(evp_md_ctx_st* ctx) const;
    };
    std::unique_ptr<evp_md_ctx_st, FreeContext> ctx_;
};

std::string sha256_hex(std::string_view bytes);
// Hash of a file's contents; throws std::runtime_error naming the path if it cannot be read.
std::string sha256_file(const std::string& path);

}  // namespace accelbench
