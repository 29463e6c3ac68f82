// Named random streams: a name opens once.
#include <gtest/gtest.h>

#include <stdexcept>

#include "datasets/streams.h"

namespace sirl {
namespace {

TEST(StreamSet, RefusesToOpenANameTwice) {
  StreamSet s(1);
  Rng a = s.open("x");
  EXPECT_THROW(s.open("x"), std::logic_error);
  Rng b = StreamSet(1).open("x");
  EXPECT_EQ(a.next_u64(), b.next_u64());  // a name is a pure function of (name, seed)
}

}  // namespace
}  // namespace sirl
