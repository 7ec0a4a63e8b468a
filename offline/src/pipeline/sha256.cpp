#include <openssl/evp.h>

#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "truecut/offline/field_outputs.hpp"

namespace truecut::offline {

namespace {

struct DigestContext {
  DigestContext() : ctx(EVP_MD_CTX_new()) {
    if (!ctx || EVP_DigestInit_ex(ctx, EVP_sha256(), nullptr) != 1)
      throw std::runtime_error("SHA-256: cannot initialise OpenSSL's digest");
  }
  ~DigestContext() { EVP_MD_CTX_free(ctx); }
  DigestContext(const DigestContext&) = delete;
  DigestContext& operator=(const DigestContext&) = delete;

  void update(const void* data, std::size_t size) {
    if (EVP_DigestUpdate(ctx, data, size) != 1) throw std::runtime_error("SHA-256: update failed");
  }
  std::string hex() {
    unsigned char md[EVP_MAX_MD_SIZE];
    unsigned int len = 0;
    if (EVP_DigestFinal_ex(ctx, md, &len) != 1) throw std::runtime_error("SHA-256: final failed");
    static const char* kHex = "0123456789abcdef";
    std::string s;
    for (unsigned int i = 0; i < len; ++i) {
      s += kHex[md[i] >> 4];
      s += kHex[md[i] & 15];
    }
    return s;
  }
  EVP_MD_CTX* ctx;
};

}  // namespace

std::string sha256_bytes(std::string_view bytes) {
  DigestContext d;
  d.update(bytes.data(), bytes.size());
  return d.hex();
}

std::string sha256_file(const std::filesystem::path& file) {
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> f(std::fopen(file.c_str(), "rb"), &std::fclose);
  if (!f) throw std::runtime_error(file.string() + ": cannot open to compute its SHA-256");
  DigestContext d;
  std::vector<char> buf(1 << 20);
  for (;;) {
    const std::size_t n = std::fread(buf.data(), 1, buf.size(), f.get());
    if (n > 0) d.update(buf.data(), n);
    if (n < buf.size()) {
      if (std::ferror(f.get())) throw std::runtime_error(file.string() + ": read error");
      break;
    }
  }
  return d.hex();
}

FileDigest digest_file(const std::string& role, const std::filesystem::path& file) {
  FileDigest d;
  d.role = role;
  d.path = file;
  d.sha256 = sha256_file(file);
  std::error_code ec;
  d.bytes = std::filesystem::file_size(file, ec);
  return d;
}

}  // namespace truecut::offline
