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

}  // namespace tactus::testkit
