// SHA-256 against the FIPS 180-4 example vectors (NIST "SHA256.pdf" examples): the
// wrapper around OpenSSL's EVP digest, fed whole and in pieces, and from a file.
#include "util/sha256.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "accelbench/base/temp_dir.h"

namespace accelbench {
namespace {

TEST(Sha256, EmptyString) {
    EXPECT_EQ(sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
}

TEST(Sha256, Abc) { EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"); }

// 448 bits: the padding no longer fits in the first block, so it takes a second one.
TEST(Sha256, TwoBlockMessage) {
    EXPECT_EQ(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
              "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}

// One million 'a', fed in pieces that do not line up with the 64-byte blocks.
TEST(Sha256, MillionAInUnevenPieces) {
    Sha256 hash;
    const std::string piece(997, 'a');
    size_t fed = 0;
    while (fed + piece.size() <= 1000000) {
        hash.update(piece);
        fed += piece.size();
    }
    hash.update(std::string(1000000 - fed, 'a'));
    EXPECT_EQ(hash.hex_digest(), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(Sha256, FileMatchesString) {
    TempDir dir("accelbench-sha256-test-");
    const auto path = dir.path() / "abc.txt";
    std::ofstream(path, std::ios::binary) << "abc";
    EXPECT_EQ(sha256_file(path.string()), sha256_hex("abc"));
    std::filesystem::remove(path);
    EXPECT_THROW(sha256_file(path.string()), std::runtime_error);
}

}  // namespace
}  // namespace accelbench
