#include "semrec/core/sha256.h"

#include <cstdlib>
#include <fstream>

#include <gtest/gtest.h>

#include "semrec/core/error.h"
#include "semrec/testing/test_util.h"

namespace semrec {
namespace {

std::string Hex(const std::string& text) {
  Sha256 sha;
  sha.Update(text);
  return sha.HexDigest();
}

TEST(Sha256, MatchesFips180Vectors) {
  EXPECT_EQ(Hex(""),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(Hex("abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(Hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(Sha256, ChunkingDoesNotChangeTheDigest) {
  std::string text;
  for (int i = 0; i < 1000; ++i) text += static_cast<char>('a' + (i * 7) % 26);
  for (size_t chunk : {1u, 3u, 63u, 64u, 65u, 500u}) {
    Sha256 sha;
    for (size_t i = 0; i < text.size(); i += chunk) {
      sha.Update(text.substr(i, chunk));
    }
    EXPECT_EQ(sha.HexDigest(), Hex(text)) << chunk;
  }
}

TEST(Sha256, FileDigestAgreesWithSha256sum) {
  semrec::testing::TempDir dir;
  const auto file = dir.path() / "data.bin";
  {
    std::ofstream out(file, std::ios::binary);
    for (int i = 0; i < 3'000'000; ++i)
      out.put(static_cast<char>(i * 31 + (i >> 9)));
  }
  const std::string cmd =
      "sha256sum " + file.string() + " > " + (dir.path() / "sum.txt").string();
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream sum(dir.path() / "sum.txt");
  std::string expected;
  sum >> expected;
  EXPECT_EQ(Sha256File(file), expected);
  EXPECT_THROW(Sha256File(dir.path() / "missing.bin"), IoError);
}

}  // namespace
}  // namespace semrec
