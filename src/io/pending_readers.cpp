// Readers not implemented yet in this commit (they report Status::unsupported); each moves to
// its own file as it lands.
#include "adamesh/error.h"
#include "volume_readers.h"

namespace adamesh::detail {

namespace {
[[noreturn]] void pending(const std::string& path, const char* fmt) {
  fail(Status::unsupported, path + ": " + fmt + " files are not supported yet");
}
}  // namespace

Volume read_slc(const std::string& path) { pending(path, "VolVis SLC"); }
Volume read_mrc(const std::string& path) { pending(path, "MRC"); }

}  // namespace adamesh::detail
