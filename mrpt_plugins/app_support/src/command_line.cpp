// TCLAP only splits the command line here: every option is read as text (an unlabeled multi-arg
// collects the positional tokens) and converted by this class, so that every message has the same
// form and no value is silently wrapped, truncated or defaulted.
#include <freeinit/app_support/command_line.h>
#include <freeinit/app_support/stop_signal.h>
#include <freeinit/mrpt_plugins/plugin_path.h>
#include <mrpt/3rdparty/tclap/CmdLine.h>

#include <algorithm>
#include <csignal>
#include <iostream>
#include <sstream>

namespace freeinit::app_support {

const char* const kVersion = "0.1.0";

namespace {

// Records TCLAP's outcome instead of printing its multi-line messages.
class Output : public TCLAP::CmdLineOutput {
 public:
  void usage(TCLAP::CmdLineInterface&) override { help = true; }
  void version(TCLAP::CmdLineInterface&) override { version_asked = true; }
  void failure(TCLAP::CmdLineInterface&, TCLAP::ArgException& e) override {
    std::string id = e.argId();
    if (id.rfind("Argument: ", 0) == 0) id = id.substr(10);
    const std::string what = e.error();
    if (what == "Couldn't find match for argument")
      error = id + ": unknown option";
    else if (what == "Missing a value for this argument!")
      error = id + ": missing value";
    else if (what == "Argument already set!")
      error = id + ": given twice";
    else
      error = (id == "undefined" ? "" : id + ": ") + what;
  }
  bool help = false, version_asked = false;
  std::string error;
};

std::string quoteArg(const std::string& s) { return "'" + s + "'"; }

}  // namespace

struct CommandLine::Impl {
  struct Option {
    std::string flag, name, doc, placeholder, default_text;
    bool required = false;
    std::unique_ptr<TCLAP::Arg> arg;
    std::function<const std::string&()> text;  ///< the value as given (options with values)
    std::function<bool()> is_set;
    std::function<std::string(const std::string&)> assign;  ///< returns an error or ""
    std::function<void()> mark_given;
    std::string id() const { return flag.empty() ? "--" + name : "-" + flag + " (--" + name + ")"; }
    std::string usageId() const {
      std::string s = flag.empty() ? "    --" + name : "-" + flag + ", --" + name;
      if (!placeholder.empty()) s += " " + placeholder;
      return s;
    }
  };
  struct Positional {
    std::string name, doc;
    bool required = true, many = false;
    Value<std::string>* one = nullptr;
    Value<std::vector<std::string>>* all = nullptr;
  };

  explicit Impl(const std::string& description) : cmd(description, ' ', kVersion, true) {
    cmd.setOutput(&output);
  }

  Option& add(std::string flag, std::string name, std::string doc, std::string placeholder,
              std::string default_text) {
    options.emplace_back();
    Option& o = options.back();
    o.flag = std::move(flag);
    o.name = std::move(name);
    o.doc = std::move(doc);
    o.placeholder = std::move(placeholder);
    o.default_text = std::move(default_text);
    return o;
  }
  // An option with a value, read as text; `assign` converts it.
  template <class T>
  const Value<T>& valued(std::deque<Value<T>>& store, Option& o, T default_value,
                         std::function<std::string(const std::string&, T&)> convert) {
    store.push_back({default_value, false});
    Value<T>* v = &store.back();
    auto* arg = new TCLAP::ValueArg<std::string>(o.flag, o.name, o.doc, false, "", o.placeholder);
    o.arg.reset(arg);
    cmd.add(arg);
    o.is_set = [arg] { return arg->isSet(); };
    o.assign = [arg, v, convert](const std::string&) { return convert(arg->getValue(), v->value); };
    o.mark_given = [v] { v->given = true; };
    return *v;
  }

  Output output;
  TCLAP::CmdLine cmd;
  std::deque<Option> options;
  std::vector<Positional> positionals;
  std::unique_ptr<TCLAP::UnlabeledMultiArg<std::string>> rest;
  std::unique_ptr<TCLAP::SwitchArg> plugin_path;
  std::deque<Value<std::string>> texts;
  std::deque<Value<double>> numbers;
  std::deque<Value<long long>> integers;
  std::deque<Value<bool>> switches;
  std::deque<Value<std::vector<std::string>>> lists;
};

CommandLine::CommandLine(std::string program, std::string description)
    : impl_(std::make_unique<Impl>(program + ": " + description)), program_(std::move(program)) {
  impl_->rest = std::make_unique<TCLAP::UnlabeledMultiArg<std::string>>(
      "arguments", "positional arguments", false, "ARG");
  impl_->cmd.add(impl_->rest.get());
  impl_->plugin_path = std::make_unique<TCLAP::SwitchArg>("", "plugin-path", "", false);
  impl_->cmd.add(impl_->plugin_path.get());
}

CommandLine::~CommandLine() = default;

const CommandLine::Value<std::string>& CommandLine::positional(const std::string& name,
                                                               const std::string& doc,
                                                               bool required) {
  impl_->texts.push_back({"", false});
  impl_->positionals.push_back({name, doc, required, false, &impl_->texts.back(), nullptr});
  return impl_->texts.back();
}

const CommandLine::Value<std::vector<std::string>>& CommandLine::positionals(
    const std::string& name, const std::string& doc, bool required) {
  impl_->lists.push_back({{}, false});
  impl_->positionals.push_back({name, doc, required, true, nullptr, &impl_->lists.back()});
  return impl_->lists.back();
}

const CommandLine::Value<std::string>& CommandLine::text(const std::string& flag,
                                                         const std::string& name,
                                                         const std::string& doc,
                                                         const std::string& default_value,
                                                         const std::string& placeholder,
                                                         const std::string& default_text) {
  auto& o = impl_->add(
      flag, name, doc, placeholder,
      default_text.empty() ? (default_value.empty() ? "\"\"" : default_value) : default_text);
  return impl_->valued<std::string>(impl_->texts, o, default_value,
                                    [](const std::string& s, std::string& x) {
                                      x = s;
                                      return std::string();
                                    });
}

const CommandLine::Value<std::string>& CommandLine::requiredText(const std::string& flag,
                                                                 const std::string& name,
                                                                 const std::string& doc,
                                                                 const std::string& placeholder) {
  const auto& v = text(flag, name, doc, "", placeholder, "required");
  impl_->options.back().required = true;
  return v;
}

const CommandLine::Value<double>& CommandLine::number(
    const std::string& flag, const std::string& name, const std::string& doc, double default_value,
    config::Range range, const std::string& placeholder, const std::string& default_text) {
  auto& o = impl_->add(flag, name, doc + " (accepted: " + range.text() + ")", placeholder,
                       default_text.empty() ? config::formatNumber(default_value) : default_text);
  return impl_->valued<double>(impl_->numbers, o, default_value,
                               [range](const std::string& s, double& x) {
                                 double v = 0;
                                 if (std::string err = config::parseNumber(s, v); !err.empty())
                                   return err;
                                 if (!range.contains(v))
                                   return s + " is out of range: accepted " + range.text();
                                 x = v;
                                 return std::string();
                               });
}

const CommandLine::Value<long long>& CommandLine::integer(
    const std::string& flag, const std::string& name, const std::string& doc,
    long long default_value, long long min, long long max, const std::string& placeholder,
    const std::string& default_text) {
  const std::string range = std::to_string(min) + ".." + std::to_string(max);
  auto& o = impl_->add(flag, name, doc + " (accepted: " + range + ")", placeholder,
                       default_text.empty() ? std::to_string(default_value) : default_text);
  return impl_->valued<long long>(
      impl_->integers, o, default_value, [min, max, range](const std::string& s, long long& x) {
        long double v = 0;
        if (std::string err = config::parseInteger(s, -9.3e18L, 9.3e18L, v); !err.empty())
          return err;
        if (v < static_cast<long double>(min) || v > static_cast<long double>(max))
          return s + " is out of range: accepted " + range;
        x = static_cast<long long>(v);
        return std::string();
      });
}

const CommandLine::Value<std::string>& CommandLine::choice(
    const std::string& flag, const std::string& name, const std::string& doc,
    const std::string& default_value, const std::vector<std::string>& choices) {
  std::string all;
  for (const auto& c : choices) all += (all.empty() ? "" : " | ") + c;
  auto& o = impl_->add(flag, name, doc + " (" + all + ")", "NAME", default_value);
  return impl_->valued<std::string>(
      impl_->texts, o, default_value, [choices, all](const std::string& s, std::string& x) {
        if (std::find(choices.begin(), choices.end(), s) == choices.end())
          return quoteArg(s) + " is not one of " + all;
        x = s;
        return std::string();
      });
}

const CommandLine::Value<bool>& CommandLine::flag(const std::string& flag, const std::string& name,
                                                  const std::string& doc) {
  auto& o = impl_->add(flag, name, doc, "", "");
  impl_->switches.push_back({false, false});
  Value<bool>* v = &impl_->switches.back();
  auto* arg = new TCLAP::SwitchArg(flag, name, doc, false);
  o.arg.reset(arg);
  impl_->cmd.add(arg);
  o.is_set = [arg] { return arg->isSet(); };
  o.assign = [arg, v](const std::string&) {
    v->value = arg->getValue();
    return std::string();
  };
  o.mark_given = [v] { v->given = true; };
  return *v;
}

std::string CommandLine::usage() const {
  std::ostringstream os;
  os << impl_->cmd.getMessage() << "\n\nUsage: " << program_ << " [options]";
  for (const auto& p : impl_->positionals)
    os << " " << (p.required ? "<" : "[<") << p.name << (p.required ? ">" : ">]")
       << (p.many ? "..." : "");
  os << "\n";
  std::size_t width = 16;
  for (const auto& p : impl_->positionals) width = std::max(width, p.name.size() + 4);
  for (const auto& o : impl_->options) width = std::max(width, o.usageId().size() + 2);
  auto line = [&](const std::string& id, const std::string& doc) {
    std::string s = "  " + id;
    s.resize(std::max(s.size() + 2, width + 2), ' ');
    os << s << doc << "\n";
  };
  if (!impl_->positionals.empty()) os << "\nArguments:\n";
  for (const auto& p : impl_->positionals) line("<" + p.name + ">", p.doc);
  os << "\nOptions:\n";
  for (const auto& o : impl_->options)
    line(o.usageId(), o.doc + (o.required              ? " (required)"
                               : o.placeholder.empty() ? ""
                                                       : " (default: " + o.default_text + ")"));
  line("-h, --help", "print this help and exit");
  line("    --version", "print the version and exit");
  line("    --plugin-path",
       "print the MRPT plugin file that stock tools load to read our rawlogs and exit "
       "(rawlog-edit -p, rawlog-grabber -p, RawLogViewer -l)");
  return os.str();
}

int CommandLine::usageError(const std::string& what) const {
  std::cerr << program_ << ": error: " << what << "; see '" << program_ << " --help'\n";
  return 2;
}

std::optional<int> CommandLine::parse(int argc, char** argv) {
  Impl& m = *impl_;
  auto bad = [&](const std::string& what) { return usageError(what); };
  if (!m.cmd.parse(argc, argv)) {
    if (m.output.help) {
      std::cout << usage();
      return 0;
    }
    if (m.output.version_asked) {
      std::cout << program_ << " " << kVersion << "\n";
      return 0;
    }
    return bad(m.output.error.empty() ? "bad command line" : m.output.error);
  }
  if (m.plugin_path->isSet()) {
    std::cout << mrpt_plugins::pluginPath() << "\n";
    return 0;
  }
  for (auto& o : m.options) {
    if (!o.is_set()) {
      if (o.required) return bad(o.id() + ": missing (required)");
      continue;
    }
    if (const std::string err = o.assign(""); !err.empty()) return bad(o.id() + ": " + err);
    o.mark_given();
  }
  // Positional tokens, in order. TCLAP hands over anything it could not match, so a token that
  // looks like an option is an unknown one, not a file name.
  const std::vector<std::string>& tokens = m.rest->getValue();
  for (const auto& t : tokens)
    if (t.size() > 1 && t[0] == '-') return bad(t + ": unknown option");
  std::size_t required = 0;
  for (const auto& p : m.positionals) required += p.required && !p.many ? 1 : 0;
  // How many optional positional arguments get a token: those beyond the required ones.
  std::size_t optional = tokens.size() > required ? tokens.size() - required : 0;
  std::size_t next = 0;
  for (auto& p : m.positionals) {
    if (!p.many && !p.required) {
      if (optional == 0) continue;
      --optional;
    }
    if (p.many) {
      for (; next < tokens.size(); ++next) p.all->value.push_back(tokens[next]);
      p.all->given = !p.all->value.empty();
      if (p.required && !p.all->given) return bad("missing <" + p.name + ">: " + p.doc);
      continue;
    }
    if (next < tokens.size()) {
      p.one->value = tokens[next++];
      p.one->given = true;
    } else if (p.required) {
      return bad("missing <" + p.name + ">: " + p.doc);
    }
  }
  if (next < tokens.size()) return bad(quoteArg(tokens[next]) + ": unexpected argument");
  return std::nullopt;
}

int runMain(const std::string& program, const std::function<int()>& body) {
  auto report = [&](const std::string& what) {
    // One line. MRPT's exceptions come as "==== MRPT exception ====", the message lines, then
    // "Call stack backtrace:" and the stack: keep the message lines only.
    std::istringstream lines(what);
    std::string line, message;
    while (std::getline(lines, line)) {
      while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
      if (line.rfind("Call stack backtrace", 0) == 0) break;
      if (line.empty() || (line.rfind("====", 0) == 0 && line.size() > 8 &&
                           line.compare(line.size() - 4, 4, "====") == 0))
        continue;
      message += (message.empty() ? "" : " ") + line;
    }
    std::cerr << program << ": error: " << (message.empty() ? "unknown error" : message) << "\n";
    return 1;
  };
  installStopHandlers();
  try {
    return body();
  } catch (const Interrupted& e) {
    // Stopped by a signal: the outputs' set has removed what this run staged. The process then
    // ends by the same signal, so that a calling shell or script sees it (status 128 + signal).
    std::cout.flush();
    std::cerr << program << ": stopped by " << signalName(e.signal())
              << "; no output of this run was written\n";
    std::cerr.flush();
    std::signal(e.signal(), SIG_DFL);
    std::raise(e.signal());
    return 128 + e.signal();
  } catch (const std::exception& e) {
    return report(e.what());
  } catch (...) {
    return report("unknown error");
  }
}

}  // namespace freeinit::app_support
