#pragma once
/// \file scalar_traits.hpp
/// Eigen::NumTraits for the library's double-like scalar types (flop_count.hpp's Counted,
/// simd_scalar.hpp's Lanes4, the tests' extended-precision scalars): one definition of the
/// traits they share. A scalar S declares `template <> struct Eigen::NumTraits<S> :
/// incise::RealScalarTraits<S> {};` and redefines only what differs (e.g. epsilon()).

#include <Eigen/Core>

namespace incise {

/// NumTraits of a real, signed, non-integer scalar S that behaves like (and converts from)
/// double: Eigen's cost model counts one unit per read, add and multiply; epsilon, precision
/// and range are double's.
template <class S>
struct RealScalarTraits : Eigen::GenericNumTraits<double> {
  using Real = S;
  using NonInteger = S;
  using Nested = S;
  using Literal = S;
  enum {
    IsComplex = 0,
    IsInteger = 0,
    IsSigned = 1,
    RequireInitialization = 1,
    ReadCost = 1,
    AddCost = 1,
    MulCost = 1
  };
  static inline Real epsilon() { return Real(Eigen::NumTraits<double>::epsilon()); }
  static inline Real dummy_precision() { return Real(Eigen::NumTraits<double>::dummy_precision()); }
  static inline Real highest() { return Real(Eigen::NumTraits<double>::highest()); }
  static inline Real lowest() { return Real(Eigen::NumTraits<double>::lowest()); }
  static inline int digits10() { return Eigen::NumTraits<double>::digits10(); }
};

}  // namespace incise
