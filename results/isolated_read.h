// Reading a file someone else wrote without letting it crash the process. A results, shard,
// dataset or embeddings file travels (a cluster's shards, a colleague's --against file, a file
// downloaded with a paper), and its checksum frame proves only that it was not damaged by
// accident: anyone can recompute XXH3 over crafted bytes. Crafted HDF5 metadata (a variable-length
// string whose global-heap reference points anywhere) crashes libhdf5 itself, below any check we
// can make through its API. So an untrusted read runs first in a forked child: if the child dies,
// the parent throws one H5Error naming the file; if it succeeds, the parent reads the same bytes
// the same way and cannot crash either. The child's memory and CPU time are bounded by the
// file's size (isolated_read.cpp, ReadBudget): crafted metadata can claim far more than the file
// stores, and HDF5 allocates what it claims.
#pragma once
#include <functional>
#include <string>

namespace sirl {

// Runs `read` (which reads `path` and throws std::exception for anything malformed) in a forked
// child, then returns; throws H5Error with the child's message if it threw, or with one line
// saying the file's HDF5 structures are malformed if it died by a signal or sanitizer exit, or
// which bound it broke where the bound ended the read (an allocation of ours that failed, the
// sanitizers' count, the CPU limit). An allocation inside HDF5 that the limit refuses fails there,
// and the child's message is HDF5's read error.
// `read` must not write outside the child (it runs in a copy of the process).
void read_in_child_first(const std::string& path, const std::function<void()>& read);

}  // namespace sirl
