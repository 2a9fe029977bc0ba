// Robustness: random truncations and byte mutations of valid files in every format either
// load or throw ParseError — never another exception, never a crash (ASan in CI).

#include <incise/io/read_mesh.hpp>
#include <incise/io/write_mesh.hpp>
#include <incise/mesh/generators.hpp>
#include <incise_test/seed.hpp>

#include <fstream>
#include <iostream>
#include <random>

#include "io_test_util.hpp"

namespace incise::io {
namespace {

std::string slurp(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void fuzz(const std::string& name, const std::string& good, std::mt19937_64& rng, int trials,
          const std::string& partner_name = "", const std::string& partner = "") {
  const char* alphabet = "0123456789 .-+eE\n#$naifx";
  int parsed = 0, rejected = 0;
  for (int t = 0; t < trials; ++t) {
    std::string s = good;
    const int kind = static_cast<int>(rng() % 3);
    if (kind == 0) {
      s.resize(rng() % s.size());
    } else {
      const int edits = 1 + static_cast<int>(rng() % 4);
      for (int e = 0; e < edits; ++e) {
        const std::size_t pos = rng() % s.size();
        const char c = alphabet[rng() % 25];
        if (kind == 1)
          s[pos] = c;
        else
          s.insert(pos, 1, c);
      }
    }
    if (!partner_name.empty()) test::write_temp(partner_name, partner);
    const std::string path = test::write_temp(name, s);
    try {
      (void)read_mesh(path);
      ++parsed;
    } catch (const ParseError&) {
      ++rejected;
    } catch (const std::exception& e) {
      ADD_FAILURE() << "trial " << t << ": non-ParseError exception " << e.what();
    }
  }
  std::cout << name << ": " << parsed << " parsed, " << rejected << " rejected\n";
  // Both outcomes occur (a fuzzer that never parses or never rejects tests nothing).
  EXPECT_GT(rejected, 0);
  EXPECT_GT(parsed, 0);
}

TEST(Fuzz, MutatedFilesLoadOrThrowParseError) {
  INCISE_SEEDED_RNG(rng, 2024);
  const mesh::MeshData m = mesh::make_box(2, 2, 1, 1, 1, 1);
  const int trials = incise::test::scaled(400);
  const std::string g22 = test::temp_path("fz22.msh"), g41 = test::temp_path("fz41.msh"),
                    me = test::temp_path("fz.mesh"), tg = test::temp_path("fzsrc");
  write_gmsh(g22, m, 22);
  write_gmsh(g41, m, 41);
  write_medit(me, m);
  write_tetgen(tg, m);
  fuzz("fz22m.msh", slurp(g22), rng, trials);
  fuzz("fz41m.msh", slurp(g41), rng, trials);
  fuzz("fzm.mesh", slurp(me), rng, trials);
  fuzz("fzt.ele", slurp(tg + ".ele"), rng, trials, "fzt.node", slurp(tg + ".node"));
  fuzz("fzt2.node", slurp(tg + ".node"), rng, trials, "fzt2.ele", slurp(tg + ".ele"));
  const mesh::MeshData tri = mesh::make_rectangle(2, 2, 1, 1);
  const std::string off = test::temp_path("fz.off");
  write_off(off, tri);
  fuzz("fzm.off", slurp(off), rng, trials);
}

}  // namespace
}  // namespace incise::io
