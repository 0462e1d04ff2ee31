// Scratch folders for hosted tests (POSIX): a fresh folder under the working directory,
// removed with everything in it when the TempDir goes out of scope.
#pragma once

#include <stdlib.h>

#include <cstdio>
#include <cstdlib>
#include <string>

namespace hivecal::test {

/// A fresh folder "<prefix>_XXXXXX" in the working directory; "" if it cannot be made.
inline std::string make_temp_dir(const char* prefix = "hivecal_cmd") {
  std::string pattern = std::string(prefix) + "_XXXXXX";
  return ::mkdtemp(pattern.data()) != nullptr ? pattern : std::string();
}

/// A scratch folder that removes itself.
class TempDir {
 public:
  explicit TempDir(const char* prefix = "hivecal_test") : path_(make_temp_dir(prefix)) {}
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  ~TempDir() {
    if (!path_.empty()) (void)std::system(("rm -rf '" + path_ + "'").c_str());
  }
  /// The folder (relative to the working directory).
  const std::string& path() const { return path_; }
  /// Writes `content` to the file `name` in the folder; returns its path.
  std::string write(const std::string& name, const std::string& content) const {
    const std::string file = path_ + "/" + name;
    std::FILE* f = std::fopen(file.c_str(), "wb");
    if (f != nullptr) {
      std::fwrite(content.data(), 1, content.size(), f);
      std::fclose(f);
    }
    return file;
  }

 private:
  std::string path_;
};

}  // namespace hivecal::test
