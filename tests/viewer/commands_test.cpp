// Splitting and checking command lines of the viewer's command language.
#include <gtest/gtest.h>

#include "commands.h"
#include "zeroset/error.h"

namespace zeroset::viewer {
namespace {

TEST(Commands, SplitKeepsTheRestOfTheLineForEquations) {
  const CommandLine c = split_command("  equation  x^2 + y^2 = z^2  ");
  EXPECT_EQ(c.name, "equation");
  EXPECT_EQ(c.rest, "x^2 + y^2 = z^2");
  EXPECT_EQ(c.args.size(), 5u);
}

TEST(Commands, CommentsAndBlankLinesAreEmpty) {
  EXPECT_TRUE(split_command("").is_empty());
  EXPECT_TRUE(split_command("   \t ").is_empty());
  EXPECT_TRUE(split_command("  # param mu 2").is_empty());
}

TEST(Commands, UnknownCommandListsTheKnownOnes) {
  try {
    check_command(split_command("parm mu 2"));
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("unknown command 'parm'"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("param"), std::string::npos);
  }
}

TEST(Commands, WrongArgumentCountShowsTheUsage) {
  try {
    check_command(split_command("param mu"));
    FAIL();
  } catch (const InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("param NAME VALUE"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(check_command(split_command("play")));
  EXPECT_NO_THROW(check_command(split_command("play mu")));
  EXPECT_THROW(check_command(split_command("play mu nu")), InvalidArgument);
}

TEST(Commands, NumbersAndSwitchesAreParsedStrictly) {
  EXPECT_EQ(parse_number("2.5", "x"), 2.5);
  EXPECT_EQ(parse_number("-1e-3", "x"), -1e-3);
  EXPECT_THROW(parse_number("2.5x", "x"), InvalidArgument);
  EXPECT_THROW(parse_number("nan", "x"), InvalidArgument);
  EXPECT_THROW(parse_number("inf", "x"), InvalidArgument);
  EXPECT_THROW(parse_number("", "x"), InvalidArgument);
  EXPECT_EQ(parse_integer("42", "n", 0, 100), 42);
  EXPECT_THROW(parse_integer("4.2", "n", 0, 100), InvalidArgument);
  EXPECT_THROW(parse_integer("101", "n", 0, 100), InvalidArgument);
  EXPECT_TRUE(parse_on_off("on", "w"));
  EXPECT_FALSE(parse_on_off("off", "w"));
  EXPECT_THROW(parse_on_off("maybe", "w"), InvalidArgument);
}

TEST(Commands, EveryCommandHasUsageAndHelp) {
  for (const CommandInfo& c : command_table()) {
    EXPECT_EQ(c.usage.substr(0, c.name.size()), c.name);
    EXPECT_FALSE(c.help.empty()) << c.name;
    EXPECT_EQ(find_command(c.name), &c);
  }
}

}  // namespace
}  // namespace zeroset::viewer
