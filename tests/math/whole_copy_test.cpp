// WholeCopy<M> (math/whole_copy.hpp): a copy has the source's size and coefficients
// whatever the destination held (larger, smaller, default), for bounded joint vectors and
// contact Jacobians in float and double; assignment and construction from Eigen
// expressions act as M's; a WholeCopy binds to M&; fixed-size types are M unchanged.
#include "inhand/math/whole_copy.hpp"

#include <gtest/gtest.h>

#include <random>
#include <string>
#include <type_traits>

namespace {

using inhand::detail::WholeCopy;

template <typename M>
class WholeCopyTest : public ::testing::Test {};

using BoundedTypes = ::testing::Types<Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1>,
                                      Eigen::Matrix<float, Eigen::Dynamic, 1, 0, 6, 1>,
                                      Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, 6>,
                                      Eigen::Matrix<float, 2, Eigen::Dynamic, 0, 2, 6>>;
/// Test names: the scalar and the shape.
struct BoundedNames {
  template <typename M>
  static std::string GetName(int) {
    return std::string(std::is_same<typename M::Scalar, float>::value ? "float" : "double") +
           (M::ColsAtCompileTime == 1 ? "_vector" : "_matrix");
  }
};
TYPED_TEST_SUITE(WholeCopyTest, BoundedTypes, BoundedNames);

/// The run-time extent: rows of a vector, columns of a matrix with fixed rows.
template <typename M>
constexpr int kMaxExtent =
    M::ColsAtCompileTime == 1 ? M::MaxRowsAtCompileTime : M::MaxColsAtCompileTime;

template <typename M>
void resize_extent(M& m, Eigen::Index n) {
  if constexpr (M::ColsAtCompileTime == 1)
    m.resize(n);
  else
    m.resize(M::RowsAtCompileTime, n);
}

template <typename M>
M random_of_size(Eigen::Index n, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  M m;
  resize_extent(m, n);
  for (Eigen::Index k = 0; k < m.size(); ++k) m.data()[k] = static_cast<typename M::Scalar>(u(rng));
  return m;
}

TYPED_TEST(WholeCopyTest, CopiesHaveTheSourcesSizeAndCoefficients) {
  using M = TypeParam;
  static_assert(WholeCopy<M>::kBounded, "a bounded type");
  static_assert(std::is_nothrow_copy_assignable<WholeCopy<M>>::value, "noexcept copies");
  constexpr int kMax = kMaxExtent<M>;
  static_assert(kMax == 6, "the types above");
  std::mt19937 rng(7);
  for (int from = 0; from <= kMax; ++from) {
    for (int to = 0; to <= kMax; ++to) {
      const WholeCopy<M> src = random_of_size<M>(from, rng);
      WholeCopy<M> dst = random_of_size<M>(to, rng);
      dst = src;
      ASSERT_EQ(dst.rows(), src.rows());
      ASSERT_EQ(dst.cols(), src.cols());
      EXPECT_TRUE(dst == static_cast<const M&>(src)) << from << " -> " << to;
      const WholeCopy<M> constructed(src);  // NOLINT(performance-unnecessary-copy-initialization)
      EXPECT_EQ(constructed.cols(), src.cols());
      EXPECT_TRUE(constructed == static_cast<const M&>(src));
    }
  }
}

TYPED_TEST(WholeCopyTest, ExpressionsAndReferencesActAsOnTheMatrix) {
  using M = TypeParam;
  using Scalar = typename M::Scalar;
  std::mt19937 rng(11);
  const M a = random_of_size<M>(4, rng);
  WholeCopy<M> w;
  EXPECT_EQ(w.size(), M().size());  // default: M's default size
  w = a * Scalar(2);
  EXPECT_TRUE(w == a * Scalar(2));
  M& as_matrix = w;  // binds to M&
  resize_extent(as_matrix, 2);
  as_matrix.setZero();
  EXPECT_EQ(w.size(), as_matrix.size());
  EXPECT_TRUE(w.isZero());
  const WholeCopy<M> from_expression = a + a;
  EXPECT_TRUE(from_expression == a + a);
}

TEST(WholeCopy, FixedAndUnboundedTypesAreTheMatrix) {
  static_assert(!WholeCopy<Eigen::Vector3d>::kBounded, "fixed");
  static_assert(!WholeCopy<Eigen::VectorXd>::kBounded, "unbounded");
  WholeCopy<Eigen::Vector3d> f = Eigen::Vector3d(1, 2, 3);
  const WholeCopy<Eigen::Vector3d> g = f;
  EXPECT_TRUE(g == Eigen::Vector3d(1, 2, 3));
  WholeCopy<Eigen::VectorXd> d = Eigen::VectorXd::LinSpaced(7, 0.0, 6.0);
  WholeCopy<Eigen::VectorXd> e;
  e = d;
  EXPECT_EQ(e.size(), 7);
  EXPECT_TRUE(e == d);
}

}  // namespace
