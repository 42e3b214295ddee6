#pragma once

// Documentation derived from the code: a section of a file between
//   <!-- BEGIN generated: NAME -->  and  <!-- END generated: NAME -->
// must be exactly what the test renders from the code. With TEEJET_UPDATE_DOCS=1 in the
// environment the test writes the section instead (the file replaced whole, never half-written)
// and passes, so that `TEEJET_UPDATE_DOCS=1 ctest -R <test>` refreshes the docs after a change.

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>

namespace teejet::testing {

inline void expect_generated_section(const std::filesystem::path& file, std::string_view name,
                                     const std::string& expected) {
  std::ifstream in(file);
  ASSERT_TRUE(in) << "cannot read " << file;
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  const std::string begin = "<!-- BEGIN generated: " + std::string(name) + " -->\n";
  const std::string end = "<!-- END generated: " + std::string(name) + " -->";
  const auto from = text.find(begin);
  const auto to = text.find(end);
  ASSERT_NE(from, std::string::npos) << file << " has no line " << begin;
  ASSERT_NE(to, std::string::npos) << file << " has no line " << end;
  ASSERT_LT(from, to) << file << ": the END line of " << name << " comes before its BEGIN line";
  const std::string current = text.substr(from + begin.size(), to - from - begin.size());
  if (current == expected) return;
  if (const char* update = std::getenv("TEEJET_UPDATE_DOCS");
      update && std::string(update) == "1") {
    const auto temporary = std::filesystem::path(file.string() + ".new");
    {
      std::ofstream out(temporary, std::ios::trunc);
      out << text.substr(0, from + begin.size()) << expected << text.substr(to);
      ASSERT_TRUE(out.flush()) << "cannot write " << temporary;
    }
    std::filesystem::rename(temporary, file);
    return;
  }
  ADD_FAILURE() << file << ": the section " << name << " is not what the code says; run "
                << "TEEJET_UPDATE_DOCS=1 ctest -R <this test> to write it. It should read:\n"
                << expected;
}

}  // namespace teejet::testing
