#pragma once
// Basic value types shared by every stage: positions are structure-of-arrays
// (an Eigen n x 3 column-major matrix keeps x, y and z in separate arrays) and
// topology is CSR (offsets + indices).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

namespace refit {

using Index = std::uint32_t;
using Vec3 = Eigen::Vector3d;
/// n x 3, column-major: x, y and z each contiguous (SoA).
using Points = Eigen::Matrix<double, Eigen::Dynamic, 3>;

/// std::allocator, except that sizing a vector leaves trivial elements unset
/// instead of zero-filling them: a large buffer is then first touched by the
/// parallel loop that fills it, not by one thread before it.
template <class T>
struct UninitAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitAllocator<U>;
  };
  UninitAllocator() = default;
  template <class U>
  UninitAllocator(const UninitAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};
/// A vector whose resize(n) leaves new elements of trivial type unset (fill them all).
template <class T>
using UninitVector = std::vector<T, UninitAllocator<T>>;

/// Compressed rows: row r holds indices[offsets[r] .. offsets[r+1]).
struct Csr {
  std::vector<Index> offsets{0};
  UninitVector<Index> indices;  // resize() leaves them unset: every CSR build fills them all

  std::size_t rows() const { return offsets.size() - 1; }
  std::size_t row_size(std::size_t r) const { return offsets[r + 1] - offsets[r]; }
  std::span<const Index> row(std::size_t r) const {
    return {indices.data() + offsets[r], indices.data() + offsets[r + 1]};
  }
  void push_row(std::span<const Index> row) {
    indices.insert(indices.end(), row.begin(), row.end());
    offsets.push_back(static_cast<Index>(indices.size()));
  }
  void clear() {
    offsets.assign(1, 0);
    indices.clear();
  }
};

inline Vec3 row3(const Points& p, Index i) { return p.row(i).transpose(); }

/// The smooth step 3t^2 - 2t^3 of t in [0, 1]: an ease with no kink at either end.
inline double smoothstep(double t) { return t * t * (3.0 - 2.0 * t); }

}  // namespace refit
