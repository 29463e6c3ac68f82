#include "kernels/onednn_matmul.h"

#ifdef SIRL_HAVE_DNNL
#include <omp.h>

#include <map>
#include <oneapi/dnnl/dnnl.hpp>
#include <string>
#include <tuple>
#include <utility>
#endif

namespace sirl {

#ifdef SIRL_HAVE_DNNL
namespace {

struct ShapeLess {
  static auto tie(const MatmulShape& s) {
    return std::tie(s.M, s.N, s.K, s.a_rs, s.a_cs, s.b_rs, s.b_cs, s.ldc, s.accumulate, s.bf16);
  }
  bool operator()(const MatmulShape& a, const MatmulShape& b) const { return tie(a) < tie(b); }
};

struct Matmul {
  dnnl::matmul prim;
  dnnl::memory a, b, c;
};

const dnnl::engine& cpu_engine() {
  static const dnnl::engine e(dnnl::engine::kind::cpu, 0);
  return e;
}

// oneDNN sizes its blocking, and may split K, by the threads it may use: one, while it creates
// and runs a primitive (the engine spreads slices and tasks over the cores itself).
struct OneThread {
  int saved = omp_get_max_threads();
  OneThread() { omp_set_num_threads(1); }
  ~OneThread() { omp_set_num_threads(saved); }
};

Matmul* matmul_for(const MatmulShape& s) {
  thread_local std::map<MatmulShape, Matmul, ShapeLess> cache;
  if (auto it = cache.find(s); it != cache.end()) return &it->second;
  using dt = dnnl::memory::data_type;
  const dt in = s.bf16 ? dt::bf16 : dt::f32;
  const dnnl::memory::desc a_md({s.M, s.K}, in, {s.a_rs, s.a_cs});
  const dnnl::memory::desc b_md({s.K, s.N}, in, {s.b_rs, s.b_cs});
  const dnnl::memory::desc c_md({s.M, s.N}, dt::f32, {s.ldc, 1});
  dnnl::primitive_attr attr;
  if (s.accumulate) {
    dnnl::post_ops po;
    po.append_sum(1.f);
    attr.set_post_ops(po);
  }
  const auto& eng = cpu_engine();
  try {
    const dnnl::matmul::primitive_desc pd(dnnl::matmul::desc(a_md, b_md, c_md), attr, eng);
    Matmul m{dnnl::matmul(pd), dnnl::memory(a_md, eng, nullptr), dnnl::memory(b_md, eng, nullptr),
             dnnl::memory(c_md, eng, nullptr)};
    return &cache.emplace(s, std::move(m)).first->second;
  } catch (const dnnl::error&) {
    return nullptr;  // no implementation for this shape: the caller computes it
  }
}

}  // namespace

bool onednn_matmul(const MatmulShape& s, const void* A, const void* B, float* C) {
  const OneThread one;
  Matmul* m = matmul_for(s);
  if (!m) return false;
  m->a.set_data_handle(const_cast<void*>(A));
  m->b.set_data_handle(const_cast<void*>(B));
  m->c.set_data_handle(C);
  thread_local dnnl::stream strm(cpu_engine());
  try {  // callers run inside OpenMP regions, which an exception must not leave
    m->prim.execute(strm, {{DNNL_ARG_SRC, m->a}, {DNNL_ARG_WEIGHTS, m->b}, {DNNL_ARG_DST, m->c}});
    strm.wait();
  } catch (const dnnl::error&) {
    return false;
  }
  return true;
}

namespace {
// oneDNN's ISA values are bit sets, each including the ones below it.
bool effective_isa_has(dnnl::cpu_isa want) {
  return (unsigned(dnnl::get_effective_cpu_isa()) & unsigned(want)) == unsigned(want);
}
}  // namespace

bool onednn_native_bf16() {
  return effective_isa_has(dnnl::cpu_isa::avx512_core_bf16);
}
bool onednn_amx_bf16() {
  return effective_isa_has(dnnl::cpu_isa::avx512_core_amx);
}
bool onednn_avx512() {
  return effective_isa_has(dnnl::cpu_isa::avx512_core);
}

std::string onednn_isa() {
  // The richest of oneDNN's x86 ISA levels the effective one includes.
  using I = dnnl::cpu_isa;
  const std::pair<I, const char*> levels[] = {{I::avx512_core_amx, "avx512_core_amx"},
                                              {I::avx512_core_bf16, "avx512_core_bf16"},
                                              {I::avx512_core_vnni, "avx512_core_vnni"},
                                              {I::avx512_core, "avx512_core"},
                                              {I::avx2_vnni, "avx2_vnni"},
                                              {I::avx2, "avx2"},
                                              {I::avx, "avx"},
                                              {I::sse41, "sse41"}};
  for (const auto& [isa, name] : levels)
    if (effective_isa_has(isa)) return name;
  return "any";
}

#else

bool onednn_matmul(const MatmulShape&, const void*, const void*, float*) {
  return false;
}
bool onednn_native_bf16() {
  return false;
}
bool onednn_amx_bf16() {
  return false;
}
bool onednn_avx512() {
  return false;
}
std::string onednn_isa() {
  return "";
}

#endif

std::string onednn_version() {
#ifdef SIRL_HAVE_DNNL
  const dnnl_version_t* v = dnnl_version();
  return std::to_string(v->major) + "." + std::to_string(v->minor) + "." + std::to_string(v->patch);
#else
  return "not in this build";
#endif
}
}  // namespace sirl
