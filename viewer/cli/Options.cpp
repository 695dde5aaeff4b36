#include "Options.h"

#include "core/Error.h"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <sstream>

namespace ml {

void Options::flag(const std::string& name, const std::string& help) {
    decls_.push_back({name, "", help, true, std::nullopt});
}

void Options::value(const std::string& name, const std::string& valueName, const std::string& help,
                    std::optional<std::string> defaultValue) {
    decls_.push_back({name, valueName, help, false, std::move(defaultValue)});
}

void Options::positional(const std::string& name, const std::string& help) {
    positionals_.emplace_back(name, help);
}

const Options::Decl& Options::decl(const std::string& name) const {
    for (const Decl& d : decls_)
        if (d.name == name) return d;
    throw std::logic_error("option --" + name + " was never declared for " + command_);
}

void Options::parse(const std::vector<std::string>& args) {
    size_t nextPositional = 0;
    for (size_t i = 0; i < args.size(); ++i) {
        const std::string& a = args[i];
        if (a == "--help" || a == "-h") {
            helpRequested_ = true;
            return;
        }
        if (a.rfind("--", 0) == 0) {
            std::string name = a.substr(2), inlineValue;
            const size_t eq = name.find('=');
            const bool hasInline = eq != std::string::npos;
            if (hasInline) {
                inlineValue = name.substr(eq + 1);
                name = name.substr(0, eq);
            }
            const Decl* d = nullptr;
            for (const Decl& x : decls_)
                if (x.name == name) d = &x;
            if (!d)
                throw InputError(concat("unknown option '--", name, "' for '", command_, "' (see meshlight ",
                                        command_, " --help)"));
            if (d->isFlag) {
                if (hasInline) throw InputError(concat("option --", name, " takes no value"));
                values_[name] = "1";
            } else if (hasInline) {
                values_[name] = inlineValue;
            } else {
                if (i + 1 >= args.size()) throw InputError(concat("option --", name, " needs a value <", d->valueName, ">"));
                values_[name] = args[++i];
            }
            continue;
        }
        if (nextPositional >= positionals_.size())
            throw InputError(concat("unexpected argument '", a, "' for '", command_, "'"));
        positionalValues_[positionals_[nextPositional++].first] = a;
    }
    if (nextPositional < positionals_.size())
        throw InputError(concat("'", command_, "' needs <", positionals_[nextPositional].first, ">"));
}

bool Options::parseOrPrintHelp(const std::vector<std::string>& args) {
    parse(args);
    if (!helpRequested_) return true;
    std::fputs(help().c_str(), stdout);
    return false;
}

bool Options::has(const std::string& name) const {
    return values_.count(name) || decl(name).defaultValue.has_value();
}

std::string Options::str(const std::string& name) const {
    auto it = values_.find(name);
    if (it != values_.end()) return it->second;
    const Decl& d = decl(name);
    if (d.defaultValue) return *d.defaultValue;
    throw InputError(concat("'", command_, "' needs --", name, " <", d.valueName, ">"));
}

std::string Options::positionalValue(const std::string& name) const {
    auto it = positionalValues_.find(name);
    ML_ASSERT(it != positionalValues_.end(), name);
    return it->second;
}

namespace {
double parseNumber(const std::string& option, const std::string& text) {
    const char* s = text.c_str();
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(s, &end);
    if (end == s || *end != '\0' || errno == ERANGE || !std::isfinite(v))
        throw InputError(concat("option --", option, ": '", text, "' is not a finite number"));
    return v;
}
}  // namespace

int Options::integer(const std::string& name, int lo, int hi) const {
    const std::string s = str(name);
    const double v = parseNumber(name, s);
    if (v != std::floor(v) || v < lo || v > hi)
        throw InputError(concat("option --", name, ": '", s, "' is not an integer in [", lo, ", ", hi, "]"));
    return int(v);
}

double Options::number(const std::string& name, double lo, double hi) const {
    const std::string s = str(name);
    const double v = parseNumber(name, s);
    if (v < lo || v > hi) throw InputError(concat("option --", name, ": ", v, " is not in [", lo, ", ", hi, "]"));
    return v;
}

uint32_t Options::seed(const std::string& name) const {
    const std::string s = str(name);
    const double v = parseNumber(name, s);
    if (v != std::floor(v) || v < 0 || v > 4294967295.0)
        throw InputError(concat("option --", name, ": '", s, "' is not an integer in [0, 4294967295]"));
    return uint32_t(v);
}

Vec3 Options::vec3(const std::string& name) const {
    const std::string s = str(name);
    std::vector<std::string> parts;
    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, ',')) parts.push_back(item);
    if (parts.size() != 3) throw InputError(concat("option --", name, ": '", s, "' is not X,Y,Z"));
    return {parseNumber(name, parts[0]), parseNumber(name, parts[1]), parseNumber(name, parts[2])};
}

std::string Options::help() const {
    std::ostringstream os;
    os << "usage: meshlight " << command_;
    for (const auto& p : positionals_) os << " <" << p.first << ">";
    os << " [options]\n";
    for (const auto& p : positionals_) os << "  <" << p.first << ">  " << p.second << "\n";
    for (const Decl& d : decls_) {
        std::string head = "  --" + d.name + (d.isFlag ? "" : " <" + d.valueName + ">");
        os << head << std::string(head.size() < 30 ? 30 - head.size() : 1, ' ') << d.help;
        if (d.defaultValue) os << " (default " << *d.defaultValue << ")";
        os << "\n";
    }
    return os.str();
}

}  // namespace ml
