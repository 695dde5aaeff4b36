// Command-line options: one typed parser, read in one place (pbrt's
// ParameterDictionary): every option a command accepts is declared with its
// type, default and help; anything else is an error, never ignored.
#pragma once

#include "core/Math.h"

#include <map>
#include <optional>
#include <string>
#include <vector>

namespace ml {

class Options {
public:
    // `command` names the subcommand in messages ("render").
    explicit Options(std::string command) : command_(std::move(command)) {}

    // Declarations, in the order they are listed by help().
    void flag(const std::string& name, const std::string& help);
    void value(const std::string& name, const std::string& valueName, const std::string& help,
               std::optional<std::string> defaultValue = std::nullopt);
    // Positional arguments, in order.
    void positional(const std::string& name, const std::string& help);

    // Parses argv (after the subcommand). Throws InputError for an unknown
    // option, a missing value, a missing or extra positional argument.
    void parse(const std::vector<std::string>& args);
    // parse(), then, if --help was given, prints help() to stdout and
    // returns false: the command has nothing more to do.
    bool parseOrPrintHelp(const std::vector<std::string>& args);

    // A value was given or has a default.
    bool has(const std::string& name) const;
    // The command line gave it (not its default).
    bool given(const std::string& name) const { return values_.count(name) > 0; }
    bool isSet(const std::string& flagName) const { return has(flagName); }
    std::string str(const std::string& name) const;
    std::string positionalValue(const std::string& name) const;
    int integer(const std::string& name, int lo, int hi) const;
    double number(const std::string& name, double lo, double hi) const;
    uint32_t seed(const std::string& name) const;
    Vec3 vec3(const std::string& name) const;   // "X,Y,Z"

    std::string help() const;

private:
    struct Decl {
        std::string name, valueName, help;
        bool isFlag = false;
        std::optional<std::string> defaultValue;
    };
    const Decl& decl(const std::string& name) const;
    std::string command_;
    std::vector<Decl> decls_;
    std::vector<std::pair<std::string, std::string>> positionals_;  // name, help
    std::map<std::string, std::string> values_;
    std::map<std::string, std::string> positionalValues_;
    bool helpRequested_ = false;
};

}  // namespace ml
