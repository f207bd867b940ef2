// Consumer of the installed library: extract() on a built-in shape, checked, written.
#include <cstdio>

#include "adamesh/extract.h"
#include "adamesh/io.h"

int main(int argc, char** argv) {
  adamesh::ExtractOptions o;
  o.budget = adamesh::Budget::triangles;
  o.triangles = 2000;
  const adamesh::ExtractResult r = adamesh::extract("shape:torus", o);
  const adamesh::TopologyReport t = adamesh::topology(r.mesh);
  std::printf("%zu triangles, euler %lld, %lld components\n", r.mesh.num_triangles(),
              static_cast<long long>(t.euler), static_cast<long long>(t.components));
  if (argc > 1) adamesh::write_mesh(r.mesh, argv[1]);
  const bool ok = r.mesh.num_triangles() > 0 && r.mesh.num_triangles() <= 2000 && t.euler == 0 &&
                  t.components == 1 && t.closed;
  return ok ? 0 : 1;
}
