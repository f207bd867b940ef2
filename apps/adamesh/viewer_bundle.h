// The viewer's JavaScript (three.js + viewer/src/main.js, bundled by esbuild at build time) as
// bytes linked into the executable; empty when the build had no npm packages.
#pragma once

#include <string_view>

namespace adamesh::cli {

std::string_view viewer_bundle();

}  // namespace adamesh::cli
