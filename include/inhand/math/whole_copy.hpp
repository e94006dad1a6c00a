// WholeCopy<M>: an Eigen matrix type M whose copies move its whole storage at once.
//
// For a bounded M (a run-time size up to a compile-time maximum, as the joint vectors and
// contact Jacobians of a hand whose fingers have different joint counts), Eigen copies
// the coefficients in use with a loop sized at run time (alignment peeling, a packet loop
// and a tail): about 40 instructions for a 3 x 4 Jacobian. The controller copies its
// state on every tick (reactive_controller.hpp: the state is put back when a tick produces
// a non-finite value), three such members per finger. WholeCopy copies the fixed storage
// (MaxRows x MaxCols coefficients, a compile-time count the compiler turns into a few
// vector moves) and the run-time size; its constructors fill the storage with zeros, so
// every coefficient copied is one that was written. For any other M (fixed or unbounded
// size) it is M with M's copies.
//
// A WholeCopy<M> is an M (public base class): it binds to M& and const M&, and every
// Eigen expression and member of M applies. Sizes, units and frames are those of M.
// Copies are noexcept for a bounded M (no allocation); the constructors allocate only
// when M does (an unbounded run-time size).
#pragma once

#include <Eigen/Core>
#include <algorithm>

namespace inhand::detail {

template <typename M>
class WholeCopy : public M {
 public:
  using Scalar = typename M::Scalar;
  /// Run-time size with a compile-time bound: the case WholeCopy changes.
  static constexpr bool kBounded =
      M::SizeAtCompileTime == Eigen::Dynamic && M::MaxSizeAtCompileTime != Eigen::Dynamic;

  WholeCopy() noexcept(kBounded) : M() { zero_storage(); }
  WholeCopy(const WholeCopy& other) noexcept(kBounded) : M() {
    zero_storage();
    copy_from(other);
  }
  /// From any Eigen expression, as M's constructor.
  template <typename Derived>
  WholeCopy(const Eigen::MatrixBase<Derived>& other) : M() {  // NOLINT: implicit, as M's
    zero_storage();
    M::operator=(other);
  }
  WholeCopy& operator=(const WholeCopy& other) noexcept(kBounded) {
    copy_from(other);
    return *this;
  }
  /// Assignment from any Eigen expression, as M's.
  template <typename Derived>
  WholeCopy& operator=(const Eigen::MatrixBase<Derived>& other) {
    M::operator=(other);
    return *this;
  }

 private:
  void zero_storage() noexcept {
    if constexpr (kBounded) std::fill_n(this->data(), M::MaxSizeAtCompileTime, Scalar(0));
  }
  void copy_from(const WholeCopy& other) noexcept(kBounded) {
    if constexpr (kBounded) {
      this->resize(other.rows(), other.cols());
      std::copy_n(other.data(), M::MaxSizeAtCompileTime, this->data());
    } else {
      M::operator=(other);
    }
  }
};

}  // namespace inhand::detail
