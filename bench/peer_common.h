// Shared by the peer executables of the benchmark (bench/peer_*.cpp): the command line, input
// loading through adamesh (so every peer meshes exactly the samples adamesh meshes), timing and
// the JSON line each peer prints for bench/bench.py.
//
//   peer_X INPUT --iso V [--res N] [--bounds ...] --out DIR --budgets 5000,20000 [--threads N]
//
// Prints one JSON object on stdout:
//   {"method": "...", "threads": N, "peak_rss_mb": M, "extract_s": t, "extract_triangles": n,
//    "meshes": [{"budget": B, "triangles": T, "time_s": t, "path": "DIR/…ply"}, ...]}
// where time_s is the wall time of the whole peer pipeline for that mesh in memory (extraction
// plus simplification or meshing), without file I/O.
#pragma once

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "adamesh/error.h"
#include "adamesh/input.h"
#include "adamesh/io.h"
#include "adamesh/mesh.h"

namespace peer {

struct Options {
  std::string input;
  double iso = 0;
  bool has_iso = false;
  adamesh::InputOptions input_options;
  std::string out_dir = ".";
  std::vector<std::size_t> budgets;
  int threads = 0;
  std::vector<std::string> extra;  ///< peer-specific `--key value` pairs, in order
};

[[noreturn]] inline void usage(const char* prog, const std::string& why) {
  std::cerr << prog << ": " << why << "\nusage: " << prog
            << " INPUT [--iso V] [--res N] [--bounds x0,y0,z0,x1,y1,z1] --out DIR"
               " [--budgets N,N,...] [--threads N]\n";
  std::exit(1);
}

inline std::vector<double> split_numbers(const std::string& s) {
  std::vector<double> v;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ',')) v.push_back(std::stod(item));
  return v;
}

inline Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) usage(argv[0], a + " needs a value");
      return argv[++i];
    };
    if (a == "--iso") {
      o.iso = std::stod(next());
      o.has_iso = true;
    } else if (a == "--res") {
      o.input_options.resolution = std::stoi(next());
    } else if (a == "--bounds") {
      const auto b = split_numbers(next());
      if (b.size() != 6) usage(argv[0], "--bounds needs 6 numbers");
      o.input_options.bounds = adamesh::Box{{b[0], b[1], b[2]}, {b[3], b[4], b[5]}};
    } else if (a == "--label") {  // label maps: the 0/1 mask of a set of labels
      o.input_options.label = adamesh::parse_label_set(next());
    } else if (a == "--out") {
      o.out_dir = next();
    } else if (a == "--budgets") {
      for (double b : split_numbers(next())) o.budgets.push_back(static_cast<std::size_t>(b));
    } else if (a == "--threads") {
      o.threads = std::stoi(next());
    } else if (a.rfind("--", 0) == 0) {
      o.extra.push_back(a);
      o.extra.push_back(next());
    } else if (o.input.empty()) {
      o.input = a;
    } else {
      usage(argv[0], "unexpected argument " + a);
    }
  }
  if (o.input.empty()) usage(argv[0], "missing INPUT");
  return o;
}

/// Value of a peer-specific option, or empty.
inline std::optional<std::string> extra(const Options& o, const std::string& key) {
  for (std::size_t i = 0; i + 1 < o.extra.size(); i += 2)
    if (o.extra[i] == key) return o.extra[i + 1];
  return std::nullopt;
}

/// Loads the input and resolves the iso-value (the input's default for shapes).
inline adamesh::Input load(Options& o) {
  adamesh::Input in = adamesh::load_input(o.input, o.input_options);
  if (!o.has_iso) {
    if (!in.default_iso) {
      std::cerr << o.input << ": --iso is required for volume files\n";
      std::exit(1);
    }
    o.iso = *in.default_iso;
  }
  return in;
}

class Stopwatch {
 public:
  Stopwatch() : t0_(std::chrono::steady_clock::now()) {}
  double seconds() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  }

 private:
  std::chrono::steady_clock::time_point t0_;
};

inline double peak_rss_mb() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<double>(ru.ru_maxrss) / 1024.0;
}

/// Drops vertices no triangle uses and renumbers (the peers' outputs keep MC's vertex array).
inline adamesh::Mesh compact(const std::vector<float>& positions,
                             const std::vector<std::uint32_t>& triangles) {
  adamesh::Mesh m;
  std::vector<std::uint32_t> remap(positions.size() / 3, 0xffffffffu);
  m.triangles.reserve(triangles.size());
  for (std::uint32_t v : triangles) {
    if (remap[v] == 0xffffffffu) {
      remap[v] = static_cast<std::uint32_t>(m.positions.size() / 3);
      m.positions.insert(m.positions.end(), positions.begin() + 3 * v,
                         positions.begin() + 3 * v + 3);
    }
    m.triangles.push_back(remap[v]);
  }
  return m;
}

/// Runs `body`, turning adamesh errors into a one-line message and exit code 2.
template <class Body>
int run_main(const char* prog, Body&& body) {
  try {
    body();
    return 0;
  } catch (const std::exception& e) {
    std::cerr << prog << ": " << e.what() << "\n";
    return 2;
  }
}

}  // namespace peer
