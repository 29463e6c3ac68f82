#include "kernels/sparse_cholesky.h"

#include <cholmod.h>

#include <cstring>
#include <stdexcept>
#include <string>

namespace sirl {

struct SparseCholesky::Impl {
  cholmod_common common;
  cholmod_factor* L = nullptr;
};

SparseCholesky::SparseCholesky(int n, const std::vector<int>& rows, const std::vector<int>& cols,
                               const std::vector<double>& values)
    : n_(n), impl_(std::make_unique<Impl>()) {
  if (rows.size() != cols.size() || rows.size() != values.size())
    throw std::invalid_argument("SparseCholesky: triplet arrays differ in length");
  cholmod_common& c = impl_->common;
  cholmod_start(&c);
  c.print = 0;
  size_t nnz = 0;
  for (size_t i = 0; i < rows.size(); ++i) nnz += rows[i] >= cols[i];
  cholmod_triplet* T = cholmod_allocate_triplet(n, n, nnz, -1 /* lower stored */, CHOLMOD_REAL, &c);
  auto* ti = static_cast<int*>(T->i);
  auto* tj = static_cast<int*>(T->j);
  auto* tx = static_cast<double*>(T->x);
  for (size_t i = 0; i < rows.size(); ++i) {
    if (rows[i] < cols[i]) continue;
    if (rows[i] < 0 || rows[i] >= n || cols[i] < 0)
      throw std::invalid_argument("SparseCholesky: index out of range");
    ti[T->nnz] = rows[i];
    tj[T->nnz] = cols[i];
    tx[T->nnz] = values[i];
    ++T->nnz;
  }
  cholmod_sparse* A = cholmod_triplet_to_sparse(T, nnz, &c);
  cholmod_free_triplet(&T, &c);
  impl_->L = cholmod_analyze(A, &c);
  cholmod_factorize(A, impl_->L, &c);
  cholmod_free_sparse(&A, &c);
  if (c.status == CHOLMOD_NOT_POSDEF || impl_->L->minor < size_t(n)) {
    cholmod_free_factor(&impl_->L, &c);
    cholmod_finish(&c);
    throw std::invalid_argument("SparseCholesky: matrix is not positive definite");
  }
}

SparseCholesky::~SparseCholesky() {
  if (impl_->L) cholmod_free_factor(&impl_->L, &impl_->common);
  cholmod_finish(&impl_->common);
}

void SparseCholesky::solve(double* B, int k) const {
  if (k <= 0) return;
  cholmod_common c;
  cholmod_start(&c);
  c.print = 0;
  cholmod_dense b;  // a view of the caller's buffer
  b.nrow = n_;
  b.ncol = k;
  b.nzmax = size_t(n_) * k;
  b.d = n_;
  b.x = B;
  b.z = nullptr;
  b.xtype = CHOLMOD_REAL;
  b.dtype = CHOLMOD_DOUBLE;
  cholmod_dense* x = cholmod_solve(CHOLMOD_A, impl_->L, &b, &c);
  if (!x) {
    cholmod_finish(&c);
    throw std::runtime_error("SparseCholesky: solve failed");
  }
  std::memcpy(B, x->x, sizeof(double) * size_t(n_) * k);
  cholmod_free_dense(&x, &c);
  cholmod_finish(&c);
}

std::string cholmod_version() {
  return std::to_string(CHOLMOD_MAIN_VERSION) + "." + std::to_string(CHOLMOD_SUB_VERSION) + "." +
         std::to_string(CHOLMOD_SUBSUB_VERSION);
}
}  // namespace sirl
