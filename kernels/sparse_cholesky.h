// A sparse symmetric positive-definite matrix factored once with SuiteSparse CHOLMOD (LLᵀ with a
// fill-reducing ordering) and solved many times. Used for the trajectory-deformation norm.
#pragma once
#include <memory>
#include <string>
#include <vector>

namespace sirl {

class SparseCholesky {
 public:
  // A [n, n] from triplets (row, col, value) of its lower triangle (entries with row < col are
  // ignored; duplicates are summed). Throws std::invalid_argument if A is not positive definite.
  SparseCholesky(int n, const std::vector<int>& rows, const std::vector<int>& cols,
                 const std::vector<double>& values);
  ~SparseCholesky();
  SparseCholesky(const SparseCholesky&) = delete;
  SparseCholesky& operator=(const SparseCholesky&) = delete;
  int size() const { return n_; }
  // Solves A X = B for k right-hand sides: B [n, k] column-major, overwritten by X.
  // Thread-safe: the factor is read-only and every call has its own CHOLMOD workspace.
  void solve(double* B, int k) const;

 private:
  struct Impl;
  int n_;
  std::unique_ptr<Impl> impl_;
};

// CHOLMOD's version as this build compiled against it, for provenance.
std::string cholmod_version();
}  // namespace sirl
