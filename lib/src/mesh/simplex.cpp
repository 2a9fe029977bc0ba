#include <incise/core/error.hpp>
#include <incise/mesh/simplex.hpp>

#include <ostream>
#include <sstream>

namespace incise::mesh {

namespace {

// Insertion sort of a[0..n) counting transpositions; returns the parity (+1 even, −1 odd).
int sort_with_parity(std::array<Index, Simplex::kMaxCount>& a, int n) {
  int parity = 1;
  for (int i = 1; i < n; ++i)
    for (int j = i; j > 0 && a[static_cast<std::size_t>(j - 1)] > a[static_cast<std::size_t>(j)];
         --j) {
      std::swap(a[static_cast<std::size_t>(j - 1)], a[static_cast<std::size_t>(j)]);
      parity = -parity;
    }
  return parity;
}

std::uint64_t mix64(std::uint64_t x) {
  // splitmix64 finaliser.
  x ^= x >> 30;
  x *= 0xbf58476d1ce4e5b9ULL;
  x ^= x >> 27;
  x *= 0x94d049bb133111ebULL;
  x ^= x >> 31;
  return x;
}

}  // namespace

Simplex::Simplex(const Index* seq, int count, int sign) {
  INCISE_CHECK(count >= 1 && count <= kMaxCount, "Simplex: 1..4 vertices required");
  INCISE_CHECK(sign == 1 || sign == -1, "Simplex: sign must be +1 or -1");
  for (int i = 0; i < count; ++i) {
    INCISE_CHECK(seq[i] >= 0, "Simplex: vertices must be non-negative");
    v_[static_cast<std::size_t>(i)] = seq[i];
  }
  const int parity = sort_with_parity(v_, count);
  for (int i = 1; i < count; ++i)
    INCISE_CHECK(v_[static_cast<std::size_t>(i - 1)] != v_[static_cast<std::size_t>(i)],
                 "Simplex: repeated vertex " + std::to_string(v_[static_cast<std::size_t>(i)]));
  count_ = static_cast<std::int8_t>(count);
  sign_ = static_cast<std::int8_t>(sign * parity);
}

Simplex::Simplex(std::initializer_list<Index> seq, int sign)
    : Simplex(seq.begin(), static_cast<int>(seq.size()), sign) {}

int Simplex::index(Index v) const {
  for (int j = 0; j < count_; ++j)
    if (v_[static_cast<std::size_t>(j)] == v) return j;
  return -1;
}

Simplex Simplex::subn(int j) const {
  INCISE_ASSERT(count_ >= 2 && j >= 0 && j < count_, "Simplex::subn: index out of range");
  Simplex s;
  int o = 0;
  for (int i = 0; i < count_; ++i)
    if (i != j) s.v_[static_cast<std::size_t>(o++)] = v_[static_cast<std::size_t>(i)];
  s.count_ = static_cast<std::int8_t>(count_ - 1);
  // Removing aj from a sorted sequence leaves it sorted: the sign is p·(−1)^j (§7.1).
  s.sign_ = static_cast<std::int8_t>((j % 2 == 0) ? sign_ : -sign_);
  return s;
}

Simplex Simplex::subv(Index v) const {
  const int j = index(v);
  INCISE_CHECK(j >= 0, "Simplex::subv: vertex " + std::to_string(v) + " not in " + to_string());
  return subn(j);
}

Simplex Simplex::mate() const {
  Simplex s = *this;
  s.sign_ = static_cast<std::int8_t>(-sign_);
  return s;
}

Simplex Simplex::substituted(Index v, Index w) const {
  const int j = index(v);
  if (j < 0 || v == w) return *this;
  std::array<Index, kMaxCount> seq = v_;
  seq[static_cast<std::size_t>(j)] = w;
  return Simplex(seq.data(), count_, sign_);
}

Simplex Simplex::sup(Index v) const {
  INCISE_CHECK(count_ >= 1 && count_ < kMaxCount, "Simplex::sup: dimension out of range");
  std::array<Index, kMaxCount> seq{};
  seq[0] = v;
  for (int i = 0; i < count_; ++i)
    seq[static_cast<std::size_t>(i + 1)] = v_[static_cast<std::size_t>(i)];
  return Simplex(seq.data(), count_ + 1, sign_);
}

std::size_t Simplex::hash() const {
  // One multiply per position (distinct odd constants), one finalising mix.
  auto u = [this](int i) {
    return static_cast<std::uint64_t>(static_cast<std::uint32_t>(v_[static_cast<std::size_t>(i)]));
  };
  std::uint64_t h = static_cast<std::uint64_t>(count_) * 2 + (sign_ > 0 ? 1 : 0);
  h ^= u(0) * 0x9e3779b97f4a7c15ULL;
  h ^= u(1) * 0xc2b2ae3d27d4eb4fULL;
  h ^= u(2) * 0x165667b19e3779f9ULL;
  h ^= u(3) * 0xd6e8feb86659fd93ULL;
  return static_cast<std::size_t>(mix64(h));
}

std::string Simplex::to_string() const {
  std::ostringstream os;
  os << (sign_ > 0 ? '+' : '-') << '<';
  for (int i = 0; i < count_; ++i) os << (i ? "," : "") << v_[static_cast<std::size_t>(i)];
  os << '>';
  return os.str();
}

std::ostream& operator<<(std::ostream& os, const Simplex& s) {
  return os << s.to_string();
}

}  // namespace incise::mesh
