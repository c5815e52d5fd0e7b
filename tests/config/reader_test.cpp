// The validating reader on in-memory YAML: what each spec accepts and rejects. The file-based
// tests cover where errors point; these cover the scalar rules behind them.

#include "haptic/config/reader.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "haptic/config/common.hpp"
#include "test_support.hpp"

namespace haptic::config {
namespace {

using test::configErrorOf;

// A map {v: <text>} read through MapReader, as a loader would see it.
class ConfigReaderTest : public ::testing::Test {
  protected:
    static MapReader readerFor(const std::string& value_text) {
        YAML::Mark start;
        return MapReader(Field(YAML::Load("v: " + value_text),
                               std::make_shared<const std::string>("mem.yaml"), "", start));
    }

    template <typename Spec>
    static typename Spec::Value parse(const std::string& value_text, const Spec& spec) {
        MapReader reader = readerFor(value_text);
        auto value = reader.required("v", spec);
        reader.finish();
        return value;
    }

    template <typename Spec>
    static std::string rejection(const std::string& value_text, const Spec& spec) {
        const auto error = configErrorOf([&] { (void)parse(value_text, spec); });
        return error ? error->message() : std::string("<accepted>");
    }
};

TEST_F(ConfigReaderTest, IntegerForms) {
    const auto spec = spec::Integer<long>::closed(-1000, 0x7FF);
    EXPECT_EQ(parse("42", spec), 42);
    EXPECT_EQ(parse("-5", spec), -5);
    EXPECT_EQ(parse("+5", spec), 5);
    EXPECT_EQ(parse("0x7ff", spec), 0x7FF);
    EXPECT_EQ(parse("0x7FF", spec), 0x7FF);
    EXPECT_EQ(parse("0o17", spec), 15);
}

TEST_F(ConfigReaderTest, IntegerRejectsEverythingElse) {
    const auto spec = spec::Integer<int>::closed(0, 100);
    EXPECT_EQ(rejection("1.0", spec), "v: expected an integer in [0, 100], got 1.0");
    EXPECT_EQ(rejection("1e2", spec), "v: expected an integer in [0, 100], got 1e2");
    EXPECT_EQ(rejection("true", spec), "v: expected an integer in [0, 100], got true");
    EXPECT_EQ(rejection("'5'", spec), "v: expected an integer in [0, 100], got the string '5'");
    EXPECT_EQ(rejection("", spec), "v: expected an integer in [0, 100], got nothing (null)");
    EXPECT_EQ(rejection("101", spec), "v: expected an integer in [0, 100], got 101");
    EXPECT_EQ(rejection("99999999999999999999", spec),
              "v: expected an integer in [0, 100], got 99999999999999999999");
    EXPECT_EQ(rejection("1_000", spec),
              "v: expected an integer in [0, 100], got the string '1_000'");
}

TEST_F(ConfigReaderTest, RealForms) {
    const auto spec = spec::Real::closed(-10.0, 10.0);
    EXPECT_DOUBLE_EQ(parse("1", spec), 1.0);
    EXPECT_DOUBLE_EQ(parse("1.5", spec), 1.5);
    EXPECT_DOUBLE_EQ(parse("-.5", spec), -0.5);
    EXPECT_DOUBLE_EQ(parse("+2.", spec), 2.0);
    EXPECT_DOUBLE_EQ(parse("1e-3", spec), 1e-3);
    EXPECT_DOUBLE_EQ(parse("2.5E+0", spec), 2.5);
}

TEST_F(ConfigReaderTest, RealRejectsNonFiniteAndText) {
    const auto spec = spec::Real::positive(10.0);
    EXPECT_EQ(rejection(".nan", spec),
              "v: expected a number in (0, 10], got .nan (not a finite number)");
    EXPECT_EQ(rejection(".NaN", spec),
              "v: expected a number in (0, 10], got .NaN (not a finite number)");
    EXPECT_EQ(rejection("-.inf", spec),
              "v: expected a number in (0, 10], got -.inf (not a finite number)");
    EXPECT_EQ(rejection("1e999", spec),
              "v: expected a number in (0, 10], got 1e999 (not a finite number)");
    EXPECT_EQ(rejection("nan", spec), "v: expected a number in (0, 10], got the string 'nan'");
    EXPECT_EQ(rejection("0", spec), "v: expected a number in (0, 10], got 0");
    EXPECT_EQ(rejection("[1]", spec), "v: expected a number in (0, 10], got a list of 1 item");
    EXPECT_EQ(rejection("{a: 1}", spec), "v: expected a number in (0, 10], got a map");
}

TEST_F(ConfigReaderTest, BooleanIsStrict) {
    EXPECT_TRUE(parse("true", spec::Boolean{}));
    EXPECT_TRUE(parse("True", spec::Boolean{}));
    EXPECT_FALSE(parse("FALSE", spec::Boolean{}));
    for (const char* text : {"yes", "no", "on", "off", "1", "0", "'true'"}) {
        EXPECT_NE(rejection(text, spec::Boolean{}).find("expected true or false"),
                  std::string::npos)
            << text;
    }
}

TEST_F(ConfigReaderTest, TextAndIdentifier) {
    EXPECT_EQ(parse("can0", spec::Text{}), "can0");
    EXPECT_EQ(parse("'1000'", spec::Text{}), "1000");
    EXPECT_NE(rejection("1000", spec::Text{}).find("got 1000"), std::string::npos);
    EXPECT_NE(rejection("''", spec::Text{}).find("non-empty"), std::string::npos);
    EXPECT_EQ(parse("exo_2", spec::Identifier{}), "exo_2");
    EXPECT_NE(rejection("Exo", spec::Identifier{}).find("got 'Exo'"), std::string::npos);
    EXPECT_NE(rejection(std::string(32, 'a'), spec::Identifier{}).find("1 to 31"),
              std::string::npos);
}

TEST_F(ConfigReaderTest, ControlCharactersNeverBreakTheOneLineMessage) {
    const std::string message = rejection("\"a\\nb\"", spec::Integer<int>::closed(0, 1));
    EXPECT_EQ(message.find('\n'), std::string::npos);
    EXPECT_NE(message.find("'a?b'"), std::string::npos);
}

TEST_F(ConfigReaderTest, ArraysAndRanges) {
    const auto vec = spec::Reals<3>{spec::Real::closed(-1.0, 1.0)};
    EXPECT_EQ(parse("[0.5, -1, 1]", vec), (std::array<double, 3>{0.5, -1.0, 1.0}));
    EXPECT_EQ(rejection("[0.5, 2, 1]", vec), "v[1]: expected a number in [-1, 1], got 2");
    EXPECT_EQ(rejection("[1, 2, 3, 4]", vec),
              "v: expected a list of 3 items, each a number in [-1, 1], got a list of 4 items");
    EXPECT_EQ(rejection("0.5", vec),
              "v: expected a list of 3 items, each a number in [-1, 1], got 0.5");

    const auto range = spec::Range{spec::Real::closed(-90.0, 90.0)};
    EXPECT_EQ(parse("[-10, 20]", range), (Interval{-10.0, 20.0}));
    EXPECT_NE(rejection("[20, 20]", range).find("got [20, 20]"), std::string::npos);
}

TEST_F(ConfigReaderTest, EnumNamesComeFromTheTraits) {
    EXPECT_EQ(parse("info", spec::Enum<LogLevel>{}), LogLevel::kInfo);
    EXPECT_EQ(toString(LogLevel::kWarn), "warn");
    EXPECT_EQ(enumFromString<LogLevel>("nope"), std::nullopt);
    EXPECT_EQ(enumChoices<LogLevel>(), "trace|debug|info|warn|error");
}

TEST_F(ConfigReaderTest, OptionalKeysFallBackButAreStillValidated) {
    MapReader reader = readerFor("5");
    EXPECT_EQ(reader.optional("w", 7, spec::Integer<int>::closed(0, 10)), 7);
    EXPECT_EQ(reader.optional("v", 7, spec::Integer<int>::closed(0, 10)), 5);
    reader.finish();

    MapReader bad = readerFor("50");
    const auto error =
        configErrorOf([&] { (void)bad.optional("v", 7, spec::Integer<int>::closed(0, 10)); });
    ASSERT_TRUE(error.has_value());
    EXPECT_EQ(error->key(), "v");
    bad.finish();
}

TEST_F(ConfigReaderTest, FinishReportsEveryUnknownKey) {
    YAML::Mark start;
    MapReader reader(Field(YAML::Load("a: 1\nb: 2\nc: 3\nd: 4"),
                           std::make_shared<const std::string>("mem.yaml"), "", start));
    (void)reader.required("a", spec::Integer<int>::closed(0, 9));
    (void)reader.contains("z");
    const auto error = configErrorOf([&] { reader.finish(); });
    ASSERT_TRUE(error.has_value());
    EXPECT_EQ(error->key(), "b");
    EXPECT_EQ(error->line(), 2);
    EXPECT_EQ(error->message(),
              "unknown key 'b' (allowed: a, z); also unknown: 'c' (line 3), 'd' (line 4)");
}

TEST(ConfigDescribeList, Wording) {
    EXPECT_EQ(describeList(3, 3, "x"), "a list of 3 items, each x");
    EXPECT_EQ(describeList(1, 4, "x"), "a list of 1 to 4 items, each x");
    EXPECT_EQ(describeList(0, 1, "x"), "a list of 0 to 1 item, each x");
}

TEST(ConfigFormatNumber, ShortestRoundTrip) {
    EXPECT_EQ(formatNumber(0.1), "0.1");
    EXPECT_EQ(formatNumber(40.0), "40");
    EXPECT_EQ(formatNumber(-90.0), "-90");
}

}  // namespace
}  // namespace haptic::config
