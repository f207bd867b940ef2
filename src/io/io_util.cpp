#include "io_util.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

namespace adamesh::detail {

std::string lower_extension(const std::string& path) {
  std::string name = std::filesystem::path(path).filename().string();
  std::transform(name.begin(), name.end(), name.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  auto ext_of = [](const std::string& n) {
    const auto dot = n.find_last_of('.');
    return dot == std::string::npos ? std::string() : n.substr(dot);
  };
  std::string ext = ext_of(name);
  if (ext == ".gz") ext = ext_of(name.substr(0, name.size() - 3)) + ext;
  return ext;
}

}  // namespace adamesh::detail
