#include "csgtile/config/config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "test_support.h"

namespace csgtile::config {

// gtest prints Problems in failure messages (found by argument-dependent lookup, so not in the
// unnamed namespace).
void PrintTo(const Problem& p, std::ostream* out) {
  *out << "{" << p.path << ", " << p.line << ", " << p.message << "}";
}

namespace {

using nlohmann::json;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

std::filesystem::path example(const char* name) {
  return test::source_dir() / "config" / "examples" / name;
}

/// Problems of a text that must not load.
std::vector<Problem> problems_of(std::string_view yaml, const Environment& env = {}) {
  const LoadResult result = load_string(yaml, "test.yaml", env);
  EXPECT_FALSE(result.ok());
  EXPECT_FALSE(result.config.has_value());
  return result.problems;
}

/// Config of a text that must load.
Config config_of(std::string_view yaml, const Environment& env = {}) {
  const LoadResult result = load_string(yaml, "test.yaml", env);
  for (const Problem& p : result.problems) ADD_FAILURE() << format_problem("test.yaml", p);
  return result.config.value_or(Config{});
}

// ---- valid files -------------------------------------------------------------------------------

TEST(ConfigLoad, ExampleFileLoadsWithEveryValue) {
  const LoadResult result = load_file(example("csgtile.yaml"));
  ASSERT_TRUE(result.ok()) << (result.problems.empty()
                                   ? ""
                                   : format_problem(result.source, result.problems.front()));
  Config expected;
  expected.run = {"demo",     {"scenes/pavilion.json", "scenes/courtyard_block.json"},
                  "out/demo", 42,
                  4,          "EPSG:28992+5709"};
  expected.kernel = {1.0e-7, 0.005};
  expected.queue = {QueueBackend::Sqlite,
                    "",
                    "host=localhost dbname=csgtile",
                    3,
                    120,
                    20,
                    "verify-full",
                    "/etc/ssl/certs/csgtile-db-ca.pem"};
  expected.log = {LogLevel::Debug, LogFormat::Json};
  expected.metrics = {"127.0.0.1:9464"};
  expected.fetch = {{"https", "s3"},      10, 900,        1024, 30, 4294967296ull, 3, 3, "",
                    "/var/cache/csgtile", "", "eu-west-1"};
  expected.city = {250.0, 50.0, 10000000, 0.5};
  expected.fit.classes.keep = {6, 26};  // the example's only fit value that is not a default
  expected.publish = {""};
  EXPECT_EQ(*result.config, expected);
}

/// Every key of `schema` is written in `text` at its depth (two spaces a level).
void expect_written(const std::string& text, const json& schema, const std::string& indent,
                    const std::string& path) {
  for (const auto& [key, key_schema] : schema["properties"].items()) {
    const std::string key_path = path.empty() ? key : path + "." + key;
    EXPECT_THAT(text, HasSubstr("\n" + indent + key + ":")) << key_path;
    if (key_schema.value("type", "") == "object") {
      expect_written(text, key_schema, indent + "  ", key_path);
    }
  }
}

TEST(ConfigLoad, ExampleFileWritesEveryKeyOfTheSchema) {
  expect_written(test::read_file(example("csgtile.yaml")), json::parse(schema_json()), "", "");
}

TEST(ConfigLoad, MinimalExampleLoads) {
  const LoadResult result = load_file(example("minimal.yaml"));
  ASSERT_TRUE(result.ok());
  Config expected;
  expected.run.inputs = {"scene.json"};
  EXPECT_EQ(*result.config, expected);
}

TEST(ConfigLoad, EmptyTextIsAllDefaults) { EXPECT_EQ(config_of(""), Config{}); }

TEST(ConfigLoad, OnlyCommentsIsAllDefaults) {
  EXPECT_EQ(config_of("# nothing here\n\n   # still nothing\n"), Config{});
}

TEST(ConfigLoad, SectionWithoutValueIsAnEmptySection) {
  EXPECT_EQ(config_of("queue:\n  # max_attempts: 3\nlog:\n"), Config{});
}

TEST(ConfigLoad, StringKeysKeepTheScalarTextAsWritten) {
  const Config config =
      config_of("run:\n  name: 001\n  output: 1.50\nqueue:\n  sqlite_path: true\n");
  EXPECT_EQ(config.run.name, "001");
  EXPECT_EQ(config.run.output, "1.50");
  EXPECT_EQ(config.queue.sqlite_path, "true");
}

TEST(ConfigLoad, NumbersInEveryYamlSpelling) {
  const Config config = config_of(
      "run:\n  seed: 9007199254740992\nkernel:\n  linear_tolerance: 1e-3\n"
      "  chordal_tolerance: 2\n");
  EXPECT_EQ(config.run.seed, 9007199254740992u);
  EXPECT_EQ(config.kernel.linear_tolerance, 1e-3);
  EXPECT_EQ(config.kernel.chordal_tolerance, 2.0);
}

TEST(ConfigLoad, JsonTextIsYamlToo) {
  EXPECT_EQ(config_of(R"({"queue": {"backend": "postgres"}})").queue.backend,
            QueueBackend::Postgres);
}

// ---- one problem of each kind, with its key path and line -----------------------------------

TEST(ConfigProblems, UnknownKeySuggestsTheClosestKey) {
  EXPECT_THAT(
      problems_of("queue:\n  max_attmpts: 5\n"),
      ElementsAre(Problem{"queue.max_attmpts", 2, "unknown key (did you mean max_attempts?)"}));
}

TEST(ConfigProblems, UnknownKeyFarFromAnyListsTheAllowedKeys) {
  EXPECT_THAT(problems_of("log:\n  colour: red\n"),
              ElementsAre(Problem{"log.colour", 2, "unknown key; allowed: format, level"}));
}

TEST(ConfigProblems, UnknownSection) {
  EXPECT_THAT(problems_of("kernal:\n  linear_tolerance: 1e-6\n"),
              ElementsAre(Problem{"kernal", 1, "unknown key (did you mean kernel?)"}));
}

TEST(ConfigProblems, EveryUnknownKeyOfASectionIsReported) {
  EXPECT_THAT(problems_of("run:\n  nmae: a\n  sead: 2\n"),
              ElementsAre(Problem{"run.nmae", 2, "unknown key (did you mean name?)"},
                          Problem{"run.sead", 3, "unknown key (did you mean seed?)"}));
}

TEST(ConfigProblems, DuplicateKeyNamesBothLines) {
  EXPECT_THAT(problems_of("queue:\n  max_attempts: 5\n  lease_seconds: 9\n  max_attempts: 6\n"),
              ElementsAre(Problem{"queue.max_attempts", 4, "duplicate key (first on line 2)"}));
}

TEST(ConfigProblems, DuplicateSection) {
  EXPECT_THAT(problems_of("log:\n  level: info\nlog:\n  level: warn\n"),
              ElementsAre(Problem{"log", 3, "duplicate key (first on line 1)"}));
}

TEST(ConfigProblems, WrongTypeNamesExpectedAndActual) {
  EXPECT_THAT(
      problems_of("queue:\n  max_attempts: five\n"),
      ElementsAre(Problem{"queue.max_attempts", 2, "expected integer, got string \"five\""}));
}

TEST(ConfigProblems, QuotedNumberIsAString) {
  EXPECT_THAT(problems_of("queue:\n  max_attempts: \"5\"\n"),
              ElementsAre(Problem{"queue.max_attempts", 2, "expected integer, got string \"5\""}));
}

TEST(ConfigProblems, FractionForAnInteger) {
  EXPECT_THAT(problems_of("run:\n  threads: 1.5\n"),
              ElementsAre(Problem{"run.threads", 2, "expected integer, got number 1.5"}));
}

TEST(ConfigProblems, ScalarForASection) {
  EXPECT_THAT(problems_of("\nqueue: 5\n"),
              ElementsAre(Problem{"queue", 2, "expected mapping, got integer 5"}));
}

TEST(ConfigProblems, ScalarForAList) {
  EXPECT_THAT(problems_of("run:\n  inputs: a.json\n"),
              ElementsAre(Problem{"run.inputs", 2, "expected list, got string \"a.json\""}));
}

TEST(ConfigProblems, AboveMaximum) {
  EXPECT_THAT(problems_of("queue:\n  max_attempts: 500\n"),
              ElementsAre(Problem{"queue.max_attempts", 2, "must be <= 100 (got 500)"}));
}

TEST(ConfigProblems, BelowMinimum) {
  EXPECT_THAT(problems_of("kernel:\n  chordal_tolerance: 1e-9\n"),
              ElementsAre(Problem{"kernel.chordal_tolerance", 2, "must be >= 1e-06 (got 1e-09)"}));
}

TEST(ConfigProblems, ExclusiveMinimum) {
  EXPECT_THAT(problems_of("kernel:\n  linear_tolerance: 0\n"),
              ElementsAre(Problem{"kernel.linear_tolerance", 2, "must be > 0 (got 0)"}));
}

TEST(ConfigProblems, SeedAboveTwoToThe53) {
  EXPECT_THAT(
      problems_of("run:\n  seed: 9007199254740993\n"),
      ElementsAre(Problem{"run.seed", 2, "must be <= 9007199254740992 (got 9007199254740993)"}));
}

TEST(ConfigProblems, BadEnumValueSuggestsTheClosestValue) {
  EXPECT_THAT(problems_of("queue:\n  backend: sqllite\n"),
              ElementsAre(Problem{"queue.backend", 2,
                                  "must be one of sqlite, postgres (got string \"sqllite\"; did "
                                  "you mean sqlite?)"}));
}

TEST(ConfigProblems, BadEnumValueFarFromAny) {
  EXPECT_THAT(problems_of("log:\n  level: 3\n"),
              ElementsAre(Problem{"log.level", 2,
                                  "must be one of trace, debug, info, warn, error (got string "
                                  "\"3\")"}));
}

TEST(ConfigProblems, BadSslModeListsTheEmptyChoiceQuoted) {
  EXPECT_THAT(problems_of("queue:\n  postgres_sslmode: verify_full\n"),
              ElementsAre(Problem{"queue.postgres_sslmode", 2,
                                  "must be one of \"\", disable, allow, prefer, require, "
                                  "verify-ca, verify-full (got string \"verify_full\"; did you "
                                  "mean verify-full?)"}));
}

TEST(ConfigLoad, PostgresTlsOptions) {
  const Config config = config_of(
      "queue:\n  backend: postgres\n  postgres_dsn: postgresql://db.example/csgtile\n"
      "  postgres_sslrootcert: /etc/ca.pem\n",
      {{"CSGTILE_QUEUE__POSTGRES_SSLMODE", "verify-ca"}});
  EXPECT_EQ(config.queue.backend, QueueBackend::Postgres);
  EXPECT_EQ(config.queue.postgres_sslmode, "verify-ca");
  EXPECT_EQ(config.queue.postgres_sslrootcert, "/etc/ca.pem");
  // The password is read from the environment by the worker, not by the config.
  EXPECT_THAT(problems_of("queue:\n  postgres_password: x\n"),
              ElementsAre(testing::Field(&Problem::path, "queue.postgres_password")));
  EXPECT_EQ(config_of("", {{"CSGTILE_PG_PASSWORD", "secret"}}), Config{});
}

TEST(ConfigProblems, NameOutsideItsPattern) {
  EXPECT_THAT(problems_of("run:\n  name: my run\n"),
              ElementsAre(Problem{"run.name", 2,
                                  "must match \"^[A-Za-z0-9_-]{1,64}$\" (got string \"my run\")"}));
}

TEST(ConfigProblems, EmptyStringsAndListItemsByIndex) {
  EXPECT_THAT(problems_of("run:\n  output: ''\n  inputs:\n    - a.json\n    - ''\n"),
              ElementsAre(Problem{"run.output", 2, "must not be empty"},
                          Problem{"run.inputs[1]", 5, "must not be empty"}));
}

TEST(ConfigProblems, NullValue) {
  EXPECT_THAT(problems_of("run:\n  seed:\n"),
              ElementsAre(Problem{"run.seed", 2, "expected integer, got null"}));
}

TEST(ConfigProblems, TypoDuplicateAndWrongTypeAreAllReported) {
  const char* yaml =
      "run:\n"
      "  name: demo\n"
      "  thraeds: 4\n"  // line 3: typo
      "queue:\n"
      "  max_attempts: 3\n"
      "  lease_seconds: ten\n"  // line 6: wrong type
      "  max_attempts: 4\n";    // line 7: duplicate
  EXPECT_THAT(problems_of(yaml),
              ElementsAre(Problem{"run.thraeds", 3, "unknown key (did you mean threads?)"},
                          Problem{"queue.lease_seconds", 6, "expected integer, got string \"ten\""},
                          Problem{"queue.max_attempts", 7, "duplicate key (first on line 5)"}));
}

TEST(ConfigProblems, SyntaxErrorHasTheLineOfTheParser) {
  const std::vector<Problem> problems = problems_of("run:\n  inputs: [a.json, b.json\nlog:\n");
  ASSERT_EQ(problems.size(), 1u);
  EXPECT_EQ(problems[0].path, "");
  EXPECT_GE(problems[0].line, 2);
  EXPECT_THAT(problems[0].message, HasSubstr("YAML syntax error"));
}

TEST(ConfigProblems, BadIndentationIsASyntaxError) {
  EXPECT_THAT(problems_of("run:\n  name: a\n   seed: 2\n"),
              ElementsAre(Problem{"", 3, "YAML syntax error: illegal map value"}));
}

TEST(ConfigProblems, TopLevelMustBeAMapping) {
  EXPECT_THAT(
      problems_of("- run\n- log\n"),
      ElementsAre(Problem{"", 1,
                          "the top level must be a mapping of sections (city, fetch, fit, kernel, "
                          "log, metrics, publish, queue, run), got a list"}));
  EXPECT_THAT(problems_of("just text\n"), ElementsAre(testing::Field(&Problem::line, 1)));
}

TEST(ConfigProblems, CityHaloMustBeSmallerThanTheCell) {
  EXPECT_THAT(problems_of("city:\n  cell_size: 100\n  halo: 100\n"),
              ElementsAre(Problem{"city.halo", 0,
                                  "must be smaller than city.cell_size (100.0), got 100.0"}));
  EXPECT_EQ(config_of("city:\n  cell_size: 100\n  halo: 20\n").city.halo, 20.0);
}

TEST(ConfigProblems, PublishUrlMustBeAnS3Prefix) {
  EXPECT_EQ(config_of("publish:\n  url: s3://city-bucket/runs\n").publish.url,
            "s3://city-bucket/runs");
  EXPECT_EQ(problems_of("publish:\n  url: http://example.org/x\n").size(), 1u);
}

TEST(ConfigProblems, MoreThanOneDocument) {
  EXPECT_THAT(
      problems_of("run:\n  seed: 2\n---\nrun:\n  seed: 3\n"),
      ElementsAre(testing::Field(&Problem::message, "expected one YAML document, found 2")));
}

TEST(ConfigProblems, MissingFileNamesThePathAndTheReason) {
  const LoadResult result = load_file("/nonexistent/csgtile.yaml");
  EXPECT_FALSE(result.ok());
  ASSERT_THAT(result.problems,
              ElementsAre(Problem{"", 0, "cannot read file: No such file or directory"}));
  EXPECT_EQ(format_problem(result.source, result.problems[0]),
            "/nonexistent/csgtile.yaml: cannot read file: No such file or directory");
}

TEST(ConfigProblems, DirectoryIsNotAFile) {
  const LoadResult result = load_file(test::source_dir() / "config");
  EXPECT_THAT(result.problems, ElementsAre(Problem{"", 0, "cannot read file: Is a directory"}));
}

TEST(ConfigProblems, HostileTextNeverThrows) {
  const std::vector<std::string> texts = {
      "[", "{a: [}", "\t- x", "run: &a [*a]", std::string("run:\n  name: \xff\xfe\n"),
      std::string(5000, '['), "? [a, b]\n: c\n", "~: 1\n", "run: !!binary aGVsbG8=\n",
      "run:\n  inputs: {a: 1}\n", std::string("run:\n  name: a\0b\n", 17), "a: &a [*a, *a]\n",
      // "Billion laughs": each level doubles the values.
      "a: &a [x, x]\nb: &b [*a, *a]\nc: &c [*b, *b]\nd: &d [*c, *c]\ne: &e [*d, *d]\n"
      "f: &f [*e, *e]\ng: &g [*f, *f]\nh: &h [*g, *g]\ni: &i [*h, *h]\nj: &j [*i, *i]\n"
      "k: &k [*j, *j]\nl: &l [*k, *k]\nm: &m [*l, *l]\nn: &n [*m, *m]\no: &o [*n, *n]\n"
      "p: &p [*o, *o]\nq: &q [*p, *p]\nr: &r [*q, *q]\ns: &s [*r, *r]\nt: &t [*s, *s]\n"};
  for (const std::string& text : texts) {
    LoadResult result;
    EXPECT_NO_THROW(result = load_string(text, "hostile.yaml")) << text.substr(0, 40);
    EXPECT_FALSE(result.ok()) << text.substr(0, 40);
    for (const Problem& p : result.problems) EXPECT_FALSE(p.message.empty());
  }
}

TEST(ConfigLoad, LoadsFromManyThreadsAtOnce) {
  const std::string text = test::read_file(example("csgtile.yaml"));
  const Config expected = config_of(text);
  std::vector<std::thread> threads;
  std::atomic<int> matches = 0;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&] {
      for (int i = 0; i < 20; ++i) {
        const LoadResult result = load_string(text, "threads.yaml");
        if (result.ok() && *result.config == expected) ++matches;
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  EXPECT_EQ(matches, 80);
}

// ---- environment overrides ---------------------------------------------------------------------

TEST(ConfigEnvironment, OverrideWinsOverTheFile) {
  const Config config =
      config_of("queue:\n  max_attempts: 3\n", {{"CSGTILE_QUEUE__MAX_ATTEMPTS", "7"}});
  EXPECT_EQ(config.queue.max_attempts, 7);
}

TEST(ConfigEnvironment, NamesAreCaseInsensitive) {
  const Config config =
      config_of("", {{"CSGTILE_queue__Backend", "postgres"}, {"CSGTILE_LOG__LEVEL", "warn"}});
  EXPECT_EQ(config.queue.backend, QueueBackend::Postgres);
  EXPECT_EQ(config.log.level, LogLevel::Warn);
}

TEST(ConfigEnvironment, InputsAreACommaSeparatedList) {
  const Config config =
      config_of("run:\n  inputs: [old.json]\n", {{"CSGTILE_RUN__INPUTS", "a.json, b.json,c.json"}});
  EXPECT_EQ(config.run.inputs, (std::vector<std::string>{"a.json", "b.json", "c.json"}));
  EXPECT_TRUE(
      config_of("run:\n  inputs: [old.json]\n", {{"CSGTILE_RUN__INPUTS", ""}}).run.inputs.empty());
}

TEST(ConfigEnvironment, StringValuesAreTakenAsWritten) {
  const Config config = config_of(
      "", {{"CSGTILE_RUN__NAME", "007"}, {"CSGTILE_QUEUE__POSTGRES_DSN", "postgres://u@h/db"}});
  EXPECT_EQ(config.run.name, "007");
  EXPECT_EQ(config.queue.postgres_dsn, "postgres://u@h/db");
}

TEST(ConfigMetrics, ListenAddressFormsAndOverride) {
  EXPECT_EQ(config_of("").metrics.listen, "");  // off by default
  for (const char* ok :
       {"off", "127.0.0.1:9464", "0.0.0.0:9464", ":9464", "9464", "[::1]:9464", "localhost:0"}) {
    EXPECT_EQ(config_of(std::string("metrics:\n  listen: \"") + ok + "\"\n").metrics.listen, ok);
  }
  EXPECT_EQ(config_of("", {{"CSGTILE_METRICS__LISTEN", "127.0.0.1:9500"}}).metrics.listen,
            "127.0.0.1:9500");
  EXPECT_THAT(problems_of("metrics:\n  listen: \"db.example:9464\"\n"),
              ElementsAre(testing::Field(&Problem::path, "metrics.listen")));
  EXPECT_EQ(config_of("metrics:\n  listen: 9464\n").metrics.listen, "9464");  // text as written
  EXPECT_THAT(problems_of("metrics:\n  port: 9464\n"),
              ElementsAre(testing::Field(&Problem::path, "metrics.port")));
}

TEST(ConfigFetch, SchemesAreCheckedAndOverridable) {
  EXPECT_EQ(config_of("").fetch.schemes, (std::vector<std::string>{"file", "http", "https", "s3"}));
  EXPECT_EQ(config_of("fetch:\n  schemes: [https]\n").fetch.schemes,
            std::vector<std::string>{"https"});
  EXPECT_THAT(problems_of("fetch:\n  schemes: [https, gopher]\n"),
              ElementsAre(testing::Field(&Problem::path, "fetch.schemes[1]")));
  EXPECT_THAT(problems_of("fetch:\n  schemes: [s3, s3]\n"),
              ElementsAre(testing::Field(&Problem::path, "fetch.schemes")));
  EXPECT_EQ(config_of("", {{"CSGTILE_FETCH__SCHEMES", "s3, https"}}).fetch.schemes,
            (std::vector<std::string>{"s3", "https"}));
  EXPECT_THAT(problems_of("fetch:\n  max_redirects: 21\n  attempts: 0\n"),
              ElementsAre(testing::Field(&Problem::path, "fetch.max_redirects"),
                          testing::Field(&Problem::path, "fetch.attempts")));
}

TEST(ConfigEnvironment, BadValueNamesTheVariable) {
  EXPECT_THAT(problems_of("queue:\n  max_attempts: 3\n", {{"CSGTILE_QUEUE__MAX_ATTEMPTS", "many"}}),
              ElementsAre(Problem{"queue.max_attempts", 0,
                                  "expected integer, got string \"many\" (from environment "
                                  "variable CSGTILE_QUEUE__MAX_ATTEMPTS)"}));
  EXPECT_THAT(problems_of("", {{"CSGTILE_RUN__INPUTS", "a.json,,b.json"}}),
              ElementsAre(Problem{"run.inputs[1]", 0,
                                  "must not be empty (from environment variable "
                                  "CSGTILE_RUN__INPUTS)"}));
}

TEST(ConfigEnvironment, UnknownKeyOfAKnownSection) {
  EXPECT_THAT(problems_of("", {{"CSGTILE_QUEUE__MAX_ATTEMPT", "3"}}),
              ElementsAre(Problem{"queue.max_attempt", 0,
                                  "unknown key (did you mean max_attempts?) (from environment "
                                  "variable CSGTILE_QUEUE__MAX_ATTEMPT)"}));
}

TEST(ConfigEnvironment, UnknownSectionAndSectionAsAValue) {
  EXPECT_THAT(problems_of("", {{"CSGTILE_QEUE__BACKEND", "sqlite"}}),
              ElementsAre(testing::Field(&Problem::path, "qeue")));
  EXPECT_THAT(problems_of("", {{"CSGTILE_LOG__LEVEL__X", "1"}}),
              ElementsAre(testing::Field(&Problem::path, "log.level.x")));
}

TEST(ConfigEnvironment, VariablesWithoutDoubleUnderscoreAreIgnored) {
  EXPECT_EQ(config_of("", {{"CSGTILE_LOG_LEVEL", "bogus"},
                           {"CSGTILE_CONFIG", "x.yaml"},
                           {"OTHER__THING", "1"},
                           {"HOME", "/root"}}),
            Config{});
}

TEST(ConfigEnvironment, FileAndEnvironmentProblemsTogether) {
  EXPECT_THAT(problems_of("log:\n  level: loud\n", {{"CSGTILE_RUN__THREADS", "-1"}}),
              ElementsAre(testing::Field(&Problem::line, 2), testing::Field(&Problem::line, 0)));
}

TEST(ConfigEnvironment, ProcessEnvironmentIsRead) {
  setenv("CSGTILE_TEST_PROCESS_ENVIRONMENT", "a=b", 1);
  const Environment env = from_process_environment();
  ASSERT_TRUE(env.contains("CSGTILE_TEST_PROCESS_ENVIRONMENT"));
  EXPECT_EQ(env.at("CSGTILE_TEST_PROCESS_ENVIRONMENT"), "a=b");
  unsetenv("CSGTILE_TEST_PROCESS_ENVIRONMENT");
}

// ---- schema and canonical JSON -----------------------------------------------------------------

TEST(ConfigSchema, IsDraft07Json) {
  const json schema = json::parse(schema_json());
  EXPECT_EQ(schema.at("$schema"), "http://json-schema.org/draft-07/schema#");
  EXPECT_EQ(std::string(schema_json()),
            test::read_file(test::source_dir() / "config" / "schema" / "csgtile.schema.json"));
}

/// Every object closes its keys and every property says what it is for.
void expect_documented(const json& schema, const std::string& path) {
  if (schema.value("type", "") == "object") {
    EXPECT_EQ(schema.value("additionalProperties", true), false) << path;
  }
  const json properties = schema.value("properties", json::object());
  for (const auto& [key, property] : properties.items()) {
    const std::string property_path = path.empty() ? key : path + "." + key;
    EXPECT_TRUE(property.contains("description")) << property_path;
    EXPECT_TRUE(property.contains("type")) << property_path;
    expect_documented(property, property_path);
  }
}

TEST(ConfigSchema, EveryObjectIsClosedAndEveryPropertyDescribed) {
  expect_documented(json::parse(schema_json()), "");
}

/// Both directions, at every depth: every schema key has the struct's default, every struct
/// key is in the schema.
void expect_defaults(const json& schema, const json& defaults, const std::string& path) {
  ASSERT_TRUE(defaults.is_object()) << path;
  const json& properties = schema.at("properties");
  for (const auto& [key, key_schema] : properties.items()) {
    const std::string key_path = path.empty() ? key : path + "." + key;
    ASSERT_TRUE(defaults.contains(key)) << key_path;
    if (key_schema.value("type", "") == "object") {
      expect_defaults(key_schema, defaults.at(key), key_path);
    } else {
      ASSERT_TRUE(key_schema.contains("default")) << key_path;
      EXPECT_EQ(key_schema.at("default"), defaults.at(key)) << key_path;
    }
  }
  EXPECT_EQ(defaults.size(), properties.size()) << path;
}

TEST(ConfigSchema, DefaultsEqualTheStructDefaults) {
  const json defaults = json::parse(to_json(config_of("")));
  ASSERT_EQ(defaults, json::parse(to_json(Config{})));
  expect_defaults(json::parse(schema_json()), defaults, "");
}

TEST(ConfigJson, SameConfigGivesSameBytesAndLoadsBack) {
  const LoadResult first = load_file(example("csgtile.yaml"));
  ASSERT_TRUE(first.ok());
  const std::string text = to_json(*first.config);
  EXPECT_EQ(to_json(Config(*first.config)), text);

  const Config reloaded = config_of(text);
  EXPECT_EQ(reloaded, *first.config);
  EXPECT_EQ(to_json(reloaded), text);
}

TEST(ConfigJson, DefaultsAsCanonicalText) {
  EXPECT_EQ(
      to_json(Config{}),
      R"({"city":{"building_timeout_seconds":60.0,"cell_size":250.0,"footprints":"","footprints_id":"","footprints_layer":"","halo":50.0,"snap_angle_degrees":0.5,"snap_distance":0.005,)"
      R"("snap_escalate_to":0.02,"split_points":10000000,)"
      R"("voxel_size":0.5},)"
      R"("fetch":{"attempts":3,"ca_bundle":"","cache_dir":"","connect_timeout_seconds":10,)"
      R"("low_speed_bytes_per_second":1024,"low_speed_seconds":30,"max_bytes":8589934592,)"
      R"("max_redirects":5,"s3_endpoint":"","s3_region":"us-east-1",)"
      R"("schemes":["file","http","https","s3"],"timeout_seconds":600},)"
      R"("fit":{"classes":{"drop":[3,4,5,7,9,18],"keep":[6]},"clusters":{"min_points":40,"tolerance":0.0},)"
      R"("ground":{"cell":1.0,"enabled":true,"height":0.3,"max_height":3.0,"slope":0.2,)"
      R"("use_classification":true,)"
      R"("window":150.0},"normals":{"neighbours":16,"sharp":false},)"
      R"("outliers":{"enabled":true,"neighbours":12,"std_ratio":3.0},)"
      R"("primitives":{"angle_tolerance_deg":5.0,"blocks":true,"boxes":true,"extrusions":true,)"
      R"("max_box_depth":40.0,"max_overreach":0.25,"min_angular_span_deg":90.0,)"
      R"("min_box_thickness":0.04,"min_building_height":2.0,"min_building_width":1.0,)"
      R"("min_curved_coverage":0.05,"min_house_area":25.0,"min_seed_coverage":0.6,)"
      R"("revolutions":true,"roof_partition":true,"roof_parts":true,"split_houses":true},)"
      R"("ransac":{"by_evidence":false,"cluster_epsilon":0.0,"cluster_scale":1.0,)"
      R"("edges_to_smaller":false,"epsilon":0.02,)"
      R"("max_candidates":2000000,)"
      R"("max_radius":30.0,"merge_same_surface":false,"min_points":40,)"
      R"("normal_deviation_deg":25.0,"probability":0.99,)"
      R"("relabel":false,"shapes":["plane","sphere","cylinder","cone","torus"]},)"
      R"("regions":{"curvature":1.0,"enabled":false,"min_points":40,"neighbours":16,)"
      R"("smoothness_deg":10.0},"vegetation":{"curvature":0.05,"enabled":true,"radius":0.0,)"
      R"("share":0.65},"voxel":{"size":0.0}},)"
      R"("kernel":{"chordal_tolerance":0.01,"linear_tolerance":1e-07},)"
      R"("log":{"format":"auto","level":"info"},"metrics":{"listen":""},)"
      R"("publish":{"url":""},)"
      R"("queue":{"backend":"sqlite","grace_seconds":25,"job_memory_mib":0,"lease_seconds":60,"max_attempts":5,)"
      R"("postgres_dsn":"","postgres_sslmode":"","postgres_sslrootcert":"",)"
      R"("sqlite_path":""},)"
      R"("run":{"crs":"","inputs":[],"name":"csgtile","output":"out","seed":1,"threads":0}})");
}

TEST(ConfigFit, SectionLoadsWithLinesAndOverrides) {
  const LoadResult loaded = load_string(
      "fit:\n  classes:\n    keep: [6, 26]\n  ransac:\n    epsilon: 0.05\n"
      "    shapes: [plane, cylinder]\n  primitives:\n    min_building_height: 3\n",
      "fit.yaml",
      {{"CSGTILE_FIT__VOXEL__SIZE", "0.25"}, {"CSGTILE_FIT__RANSAC__MIN_POINTS", "12"}});
  ASSERT_TRUE(loaded.ok());
  const FitConfig& fit = loaded.config->fit;
  EXPECT_EQ(fit.classes.keep, (std::vector<int>{6, 26}));
  EXPECT_EQ(fit.classes.drop, (std::vector<int>{3, 4, 5, 7, 9, 18}));  // default kept
  EXPECT_EQ(fit.ransac.epsilon, 0.05);
  EXPECT_EQ(fit.ransac.shapes, (std::vector<std::string>{"plane", "cylinder"}));
  EXPECT_EQ(fit.primitives.min_building_height, 3.0);
  EXPECT_EQ(fit.voxel.size, 0.25);
  EXPECT_EQ(fit.ransac.min_points, 12);
  EXPECT_EQ(loaded.line_of("fit.ransac.epsilon"), 5);
  EXPECT_EQ(fit.normals, FitNormalsConfig{});  // untouched sections keep their defaults
}

TEST(ConfigFit, EveryProblemWithItsKeyAndLine) {
  const LoadResult loaded = load_string(
      "fit:\n  ransac:\n    epsilom: 0.02\n    min_points: 2\n    shapes: [plane, blob]\n"
      "  classes:\n    keep: [6, 300]\n  outliers:\n    neighbours: 1\n",
      "fit.yaml");
  ASSERT_FALSE(loaded.ok());
  std::vector<std::string> paths;
  for (const auto& p : loaded.problems) paths.push_back(p.path + "@" + std::to_string(p.line));
  EXPECT_THAT(paths, ::testing::IsSupersetOf({"fit.ransac.epsilom@3", "fit.ransac.min_points@4",
                                              "fit.ransac.shapes[1]@5", "fit.classes.keep[1]@7",
                                              "fit.outliers.neighbours@9"}));
}

// Scale-dependent RANSAC options may be 0 (derived from the cloud); other small or negative
// values stay errors.
TEST(ConfigFit, ZeroLeavesTheScaleToTheCloud) {
  const LoadResult zero = load_string(
      "fit:\n  ransac:\n    epsilon: 0\n    min_points: 0\n    max_radius: 0\n    relabel: true\n",
      "cad.yaml");
  ASSERT_TRUE(zero.ok());
  EXPECT_EQ(zero.config->fit.ransac.epsilon, 0.0);
  EXPECT_EQ(zero.config->fit.ransac.min_points, 0);
  EXPECT_EQ(zero.config->fit.ransac.max_radius, 0.0);
  EXPECT_TRUE(zero.config->fit.ransac.relabel);
  const LoadResult bad = load_string(
      "fit:\n  ransac:\n    epsilon: -0.1\n    min_points: 1\n    max_radius: -3\n", "bad.yaml");
  ASSERT_FALSE(bad.ok());
  std::vector<std::string> paths;
  for (const auto& p : bad.problems) paths.push_back(p.path + "@" + std::to_string(p.line));
  EXPECT_THAT(paths, ::testing::IsSupersetOf({"fit.ransac.epsilon@3", "fit.ransac.min_points@4",
                                              "fit.ransac.max_radius@5"}));
}

TEST(ConfigFit, ASectionOneLevelTooHighSaysWhereItBelongs) {
  // A fit options file of older versions ({"ransac": {...}}) is not a config.
  const LoadResult loaded = load_string(R"({"ransac": {"epsilon": 0.02}})", "old.json");
  ASSERT_EQ(loaded.problems.size(), 1u);
  EXPECT_EQ(loaded.problems[0].path, "ransac");
  EXPECT_EQ(loaded.problems[0].message, "unknown key; fit options go under fit: (fit.ransac)");
}

TEST(ConfigFormat, OneLinePerProblem) {
  EXPECT_EQ(format_problem("file.yaml",
                           {"queue.max_attmpts", 12, "unknown key (did you mean max_attempts?)"}),
            "file.yaml:12: queue.max_attmpts: unknown key (did you mean max_attempts?)");
  EXPECT_EQ(format_problem("file.yaml", {"queue.max_attempts", 0, "bad"}),
            "file.yaml: queue.max_attempts: bad");
  EXPECT_EQ(format_problem("file.yaml", {"", 3, "YAML syntax error: x"}),
            "file.yaml:3: YAML syntax error: x");
}

}  // namespace
}  // namespace csgtile::config
