// The message of the springy::Error a call throws, for tests of error messages.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "sim/error.h"

namespace springy::test {

// The message of the springy::Error that `f` throws; fails the test if it throws nothing.
template <typename F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected springy::Error";
  return {};
}

}  // namespace springy::test
