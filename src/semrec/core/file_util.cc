#include "semrec/core/file_util.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>

#include "semrec/core/error.h"

namespace fs = std::filesystem;

namespace semrec {

void WriteFileAtomic(const fs::path& path,
                     const std::function<void(const fs::path&)>& write) {
  std::error_code ec;
  if (path.has_parent_path()) {
    fs::create_directories(path.parent_path(), ec);
    if (ec) {
      throw IoError(path.parent_path(),
                    "cannot create folder: " + ec.message());
    }
  }
  static std::atomic<unsigned> counter{0};
  // Keep the extension: writers such as Open3D pick the format from it.
  const fs::path tmp =
      path.parent_path() /
      (path.stem().string() + ".tmp" + std::to_string(getpid()) + "_" +
       std::to_string(counter++) + path.extension().string());
  try {
    write(tmp);
    if (!fs::exists(tmp)) throw IoError(path, "writer produced no file");
    fs::rename(tmp, path, ec);
    if (ec) {
      throw IoError(path,
                    "cannot rename temporary file into place: " + ec.message());
    }
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
}

void WriteTextFileAtomic(const fs::path& path, const std::string& content) {
  WriteFileAtomic(path, [&](const fs::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    out << content;
    out.close();
    if (!out) throw IoError(path, "write failed (disk full?)");
  });
}

std::vector<unsigned char> ReadFileBytes(const fs::path& path) {
  RequireFile(path);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, "cannot open for reading (permissions?)");
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)),
                                   std::istreambuf_iterator<char>());
  if (in.bad()) throw IoError(path, "read failed");
  return bytes;
}

std::string ReadTextFile(const fs::path& path) {
  RequireFile(path);
  std::ifstream in(path);
  if (!in) throw IoError(path, "cannot open for reading (permissions?)");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void RequireFile(const fs::path& path, const std::string& what) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw IoError(path, what + " does not exist");
  if (!fs::is_regular_file(path, ec)) {
    throw IoError(path, what + " is not a regular file");
  }
}

void RequireDirectory(const fs::path& path, const std::string& what) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw IoError(path, what + " does not exist");
  if (!fs::is_directory(path, ec)) {
    throw IoError(path, what + " is not a folder");
  }
}

void RequireEmptyOrOverwrite(const fs::path& dir, bool overwrite) {
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_empty(dir, ec) && !overwrite) {
    throw IoError(
        dir,
        "output folder is not empty (use --overwrite to replace its files)");
  }
}

std::string LowerExtension(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}

std::filesystem::path ProjectDataDir() {
  if (const char* env = std::getenv("SEMREC_DATA_DIR"); env && *env) {
    return env;
  }
  return SEMREC_DEFAULT_DATA_DIR;
}

std::filesystem::path DefaultModelDir() {
  if (const char* env = std::getenv("SEMREC_MODELS"); env && *env) return env;
  return SEMREC_DEFAULT_MODEL_DIR;
}

}  // namespace semrec
