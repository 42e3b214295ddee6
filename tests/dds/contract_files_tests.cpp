// The files that restate the DDS contract for people and for DDS-Security are held against it:
// the security roles' topic lists and the topic table of docs/topics.md name every topic the
// contract has, and no other.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "teejet/dds/topics.hpp"

namespace teejet::dds {
namespace {

const std::filesystem::path kSource = TEEJET_SOURCE_DIR;

std::string read(const std::filesystem::path& file) {
  std::ifstream in(file);
  EXPECT_TRUE(in) << "cannot read " << file;
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

template <class... Samples>
std::set<std::string> topics_of(topics::SampleTypes<Samples...>) {
  return {topics::topic_name<Samples>()...};
}

template <class... Samples>
std::set<std::pair<std::string, std::string>> topics_and_types(topics::SampleTypes<Samples...>) {
  return {{topics::topic_name<Samples>(), typename PubSubTypeOf<Samples>::type().getName()}...};
}

// Commands and layout changes: what a commander asks of a gateway.
std::set<std::string> every_topic_but_commands() {
  auto topics = topics_of(topics::EverySampleType{});
  topics.erase(topics::kCommand);
  topics.erase(topics::kLayoutChange);
  return topics;
}

// The <topic> elements inside the role's <publish> or <subscribe> element.
std::set<std::string> role_topics(const std::string& role, const std::string& direction) {
  const std::string xml = read(kSource / "config" / "security" / "roles" / (role + ".xml"));
  std::set<std::string> topics;
  const std::regex section("<" + direction + ">([\\s\\S]*?)</" + direction + ">");
  const std::regex topic("<topic>([^<]*)</topic>");
  for (std::sregex_iterator s(xml.begin(), xml.end(), section), end; s != end; ++s) {
    const std::string inside = (*s)[1];
    for (std::sregex_iterator t(inside.begin(), inside.end(), topic); t != end; ++t) {
      topics.insert((*t)[1]);
    }
  }
  return topics;
}

TEST(ContractFiles, TheGatewayRolePublishesEveryTopicButCommandsAndReadsCommandsAndStatus) {
  auto published = every_topic_but_commands();
  published.insert(topics::kEventWatchdog);
  EXPECT_EQ(role_topics("gateway", "publish"), published) << "config/security/roles/gateway.xml";
  EXPECT_EQ(role_topics("gateway", "subscribe"),
            (std::set<std::string>{topics::kCommand, topics::kLayoutChange, topics::kGatewayStatus,
                                   topics::kLocation}));
}

// Every role may write its own event watchdog's beat (dds/event_watchdog.hpp), which nobody reads.
TEST(ContractFiles, TheCommanderRoleWritesCommandsAndLayoutChangesOnly) {
  EXPECT_EQ(
      role_topics("commander", "publish"),
      (std::set<std::string>{topics::kCommand, topics::kLayoutChange, topics::kEventWatchdog}));
}

TEST(ContractFiles, TheObserverRoleReadsEveryTopicButCommands) {
  EXPECT_EQ(role_topics("observer", "subscribe"), every_topic_but_commands())
      << "config/security/roles/observer.xml";
  EXPECT_EQ(role_topics("observer", "publish"), std::set<std::string>{topics::kEventWatchdog});
}

TEST(ContractFiles, TheRecorderRoleReadsEverythingAndWritesNoValveTopic) {
  EXPECT_EQ(role_topics("recorder", "subscribe"), std::set<std::string>{"teejet/*"});
  EXPECT_EQ(role_topics("recorder", "publish"), std::set<std::string>{topics::kEventWatchdog});
}

TEST(ContractFiles, TopicsMdTabulatesEveryTopicWithItsType) {
  const std::string doc = read(kSource / "docs" / "topics.md");
  std::set<std::pair<std::string, std::string>> rows;
  const std::regex row("\\n\\| `(teejet/[a-z_/]+)` \\| `([A-Za-z:]+)` \\|");
  for (std::sregex_iterator r(doc.begin(), doc.end(), row), end; r != end; ++r) {
    rows.emplace((*r)[1], (*r)[2]);
  }
  EXPECT_EQ(rows, topics_and_types(topics::EverySampleType{})) << "docs/topics.md's table";
}

}  // namespace
}  // namespace teejet::dds
