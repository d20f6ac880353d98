#pragma once
// Runs `f` and expects a tactus::InputError whose message contains every fragment.
#include <gtest/gtest.h>

#include <initializer_list>
#include <string>

#include "tactus/core/error.hpp"

namespace tactus::testkit {

template <class F>
void expect_input_error(F&& f, std::initializer_list<std::string> fragments) {
  try {
    f();
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    for (const auto& frag : fragments) EXPECT_NE(std::string(e.what()).find(frag), std::string::npos) << e.what();
  }
}

// The message of the InputError `f` throws, or "" when it throws none (for tests that print it).
template <class F>
std::string input_error_of(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace tactus::testkit
