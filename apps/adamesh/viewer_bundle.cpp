// Links the esbuild bundle (ADAMESH_VIEWER_JS, a path set by apps/adamesh/CMakeLists.txt when
// viewer/node_modules was installed) into the executable with the assembler's .incbin, so that
// `adamesh view` needs no file at run time.
#include "viewer_bundle.h"

#ifdef ADAMESH_VIEWER_JS
asm(".pushsection .rodata\n"
    ".balign 16\n"
    "adamesh_viewer_js_begin:\n"
    ".incbin \"" ADAMESH_VIEWER_JS "\"\n"
    "adamesh_viewer_js_end:\n"
    ".byte 0\n"
    ".popsection\n");
extern "C" const char adamesh_viewer_js_begin[];
extern "C" const char adamesh_viewer_js_end[];
#endif

namespace adamesh::cli {

std::string_view viewer_bundle() {
#ifdef ADAMESH_VIEWER_JS
  return {adamesh_viewer_js_begin, static_cast<std::size_t>(adamesh_viewer_js_end - adamesh_viewer_js_begin)};
#else
  return {};
#endif
}

}  // namespace adamesh::cli
