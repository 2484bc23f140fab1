// One declaration per parameter struct drives its whole INI life: loading, validation, the echo of
// the effective configuration and the documentation checks. A struct's section declares each key
// once, with its name, unit, accepted values and a one-line doc; the default is the struct's own
// (a default-constructed struct), so it is never written twice. For example:
//
//   const config::Section<WindowParams>& windowSection() {
//     static const auto s = config::Section<WindowParams>("window")
//         .number("duration", &WindowParams::duration, "s", config::between(0.05, 60),
//                 "window length from its first IMU sample");
//     return s;
//   }
//
//   windowSection().load(ini, cfg.window);   // [window] of an IniFile, over cfg.window's values
//   windowSection().validate(cfg.window);    // the same checks on a struct filled in code
//   windowSection().dump(cfg.window, out);   // "[window]\nduration = 0.5 ; [s] ... (accepted ...)"
//
// Members are given as pointers to members or, for nested fields, as accessors
// `[](auto& s) -> auto& { return s.cloud.x.name; }`. Numbers in another unit than their member
// (a key in ms for a member in s) are declared with scaled(), so that the conversion is written
// once. A list of values is a family of numbered keys (items(): object_1, object_2, ...), its
// length another key. A key that matters only for some values of others is dumped only then
// (when()). Errors are ConfigError, one line naming the file, the line, the section and the key.
//
// A key may say what reads it (readers(), readBy(): "joint, paper"), shown at the end of its doc
// line and, for the section, in a "; read by: ..." line under its header. A key that had another
// section or name in an earlier layout declares it (formerly()): an INI written for the earlier
// layout still loads, the old names moved to the current ones by renameFormerKeys() with one
// notice per key; the dump writes only the current names.
#pragma once

#include <freeinit/io/ini_file.h>
#include <freeinit/io/number_format.h>

#include <Eigen/Core>
#include <functional>
#include <iosfwd>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace freeinit::config {

/// The accepted values of a number, in the unit of its key: an interval, either end open or
/// unbounded. Values must be finite in any case.
struct Range {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false;
  bool hi_open = false;
  bool contains(double x) const;
  /// "[0.0001, 1]", "(0, 10]", ">= 0", "> 0", "any".
  std::string text() const;
};
Range any();
Range atLeast(double lo);               ///< [lo, inf)
Range above(double lo);                 ///< (lo, inf)
Range between(double lo, double hi);    ///< [lo, hi]
Range aboveUpTo(double lo, double hi);  ///< (lo, hi]

/// A key's name in an earlier layout of the sections: [section] key.
struct FormerName {
  std::string section;
  std::string key;
};

/// What the documentation knows of a key.
struct KeyInfo {
  std::string name;
  std::string unit;                ///< "m/s", "s", "-" (a pure number), "bool", "text", ...
  std::string doc;                 ///< one line
  std::string default_value;       ///< the struct's own default, as an INI value
  std::string accepted;            ///< "[0.0001, 1]", "true | false", "a | b", "" (any text)
  std::string readers;             ///< what reads it, "joint, paper" ("": not said)
  std::vector<FormerName> former;  ///< its names in earlier layouts, still read (formerly())
};

// Value parsing and formatting shared by the key types (exposed for other loaders and tests).
/// Parses a finite decimal number (no hex, inf or nan); returns an error or "".
std::string parseNumber(std::string_view text, double& x);
/// Parses a whole number in [lo, hi]; returns an error or "".
std::string parseInteger(std::string_view text, long double lo, long double hi, long double& x);
/// Exactly `n` numbers separated by blanks; returns an error or "".
std::string parseNumbers(std::string_view text, std::size_t n, std::vector<double>& out);
/// true/false (also 1/0, yes/no, on/off), case-insensitive; returns an error or "".
std::string parseBool(std::string_view text, bool& x);
/// The shortest text that reads back as exactly x (number_format.h).
using freeinit::formatNumber;

/// Where a check reports a problem: in a file (with the key's line) or in a struct filled in
/// code ("configuration key section.key").
class Checker {
 public:
  Checker(const IniFile* file, std::string section) : file_(file), section_(std::move(section)) {}
  /// Whether the key is given in the file (always false for a struct filled in code).
  bool has(const std::string& key) const;
  /// Throws ConfigError naming the key.
  [[noreturn]] void fail(const std::string& key, const std::string& what) const;
  const IniFile* file() const { return file_; }

 private:
  const IniFile* file_;
  std::string section_;
};

/// A section's declaration without its struct type: what documentation checks and section lists
/// need.
class SectionBase {
 public:
  virtual ~SectionBase() = default;
  const std::string& name() const { return name_; }
  const std::string& doc() const { return doc_; }
  /// The declared keys, with the defaults of a default-constructed struct.
  virtual std::vector<KeyInfo> keys() const = 0;
  /// `text` read as the value of `key` and written back as the dump writes it (so that "1e-9"
  /// and "1e-09" compare equal); sets `error` (and returns "") when it is not a valid value.
  virtual std::string canonical(const std::string& key, const std::string& text,
                                std::string& error) const = 0;
  /// Keys of the section that another program reads (e.g. rawlog-grabber's `driver`): accepted,
  /// not loaded.
  const std::vector<std::string>& foreignKeys() const { return foreign_; }

 protected:
  SectionBase(std::string name, std::string doc) : name_(std::move(name)), doc_(std::move(doc)) {}
  std::string name_, doc_;
  std::vector<std::string> foreign_;
  std::vector<std::pair<std::string, std::string>> refused_;  ///< key, message
};

namespace detail {

template <class S, class M>
auto accessor(M m) {
  if constexpr (std::is_member_object_pointer_v<M>) {
    return [m](auto& s) -> auto& { return s.*m; };
  } else {
    return m;
  }
}
template <class S, class M>
using MemberType = std::remove_cv_t<
    std::remove_reference_t<decltype(accessor<S>(std::declval<M>())(std::declval<S&>()))>>;

/// One line of a dump: "key = value ; [unit] doc (accepted: ...) (readers)".
/// `commented`: the line starts with ';' (a value shown, not set).
void dumpLine(std::ostream& out, const KeyInfo& k, const std::string& value,
              bool commented = false);
std::string outOfRange(const std::string& value, const Range& r, const std::string& unit);
[[noreturn]] void unknownKey(const IniFile& ini, const std::string& section, const std::string& key,
                             const std::vector<std::string>& known);

}  // namespace detail

/// The declaration of struct S's INI section (see the top of this file).
template <class S>
class Section : public SectionBase {
 public:
  explicit Section(std::string name, std::string doc = "")
      : SectionBase(std::move(name), std::move(doc)) {}

  /// A number: a double or integer member, in `unit`, within `range`.
  template <class M>
  Section& number(std::string key, M member, std::string unit, Range range, std::string doc) {
    return scaled(std::move(key), member, std::move(unit), 1.0, range, std::move(doc));
  }
  /// A number whose key has another unit than its member: member = value / per_unit (a key in
  /// ms for a member in s: per_unit = 1000). `range` is in the key's unit.
  template <class M>
  Section& scaled(std::string key, M member, std::string unit, double per_unit, Range range,
                  std::string doc) {
    using T = detail::MemberType<S, M>;
    static_assert(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>, "number(): a number");
    auto acc = detail::accessor<S>(member);
    Key k = newKey(std::move(key), std::move(unit), std::move(doc), range.text());
    k.set = [acc, per_unit, range, unit = k.info.unit](std::string_view text, S& s) {
      std::string err;
      if constexpr (std::is_integral_v<T>) {
        long double x = 0;
        err = parseInteger(text, -1e30L, 1e30L, x);
        if (err.empty() && !range.contains(static_cast<double>(x)))
          err = detail::outOfRange(std::string(text), range, unit);
        if (err.empty() && (x < static_cast<long double>(std::numeric_limits<T>::lowest()) ||
                            x > static_cast<long double>(std::numeric_limits<T>::max())))
          err = quote(text) + " is out of range for this key";
        if (err.empty()) acc(s) = static_cast<T>(x);
      } else {
        double x = 0;
        err = parseNumber(text, x);
        if (err.empty() && !range.contains(x))
          err = detail::outOfRange(std::string(text), range, unit);
        if (err.empty()) acc(s) = static_cast<T>(x / per_unit);
      }
      return err;
    };
    k.get = [acc, per_unit](const S& s) {
      if constexpr (std::is_integral_v<T>) {
        return std::to_string(acc(s));
      } else {
        return formatNumber(static_cast<double>(acc(s)) * per_unit);
      }
    };
    k.check = [acc, per_unit, range, unit = k.info.unit](const S& s) -> std::string {
      const double x = static_cast<double>(acc(s)) * per_unit;
      return range.contains(x) ? "" : detail::outOfRange(formatNumber(x), range, unit);
    };
    return add(std::move(k));
  }

  /// A boolean (true/false).
  template <class M>
  Section& flag(std::string key, M member, std::string doc) {
    auto acc = detail::accessor<S>(member);
    Key k = newKey(std::move(key), "bool", std::move(doc), "true | false");
    k.set = [acc](std::string_view text, S& s) {
      bool x = false;
      std::string err = parseBool(text, x);
      if (err.empty()) acc(s) = x;
      return err;
    };
    k.get = [acc](const S& s) { return std::string(acc(s) ? "true" : "false"); };
    return add(std::move(k));
  }

  /// A text value (the rest of the line; "" for empty). `non_empty`: an empty value is refused.
  template <class M>
  Section& text(std::string key, M member, std::string doc, bool non_empty = false) {
    auto acc = detail::accessor<S>(member);
    Key k = newKey(std::move(key), "text", std::move(doc), non_empty ? "non-empty text" : "");
    k.set = [acc, non_empty](std::string_view text, S& s) -> std::string {
      if (non_empty && text.empty()) return "must not be empty";
      acc(s) = std::string(text);
      return "";
    };
    k.get = [acc](const S& s) { return acc(s); };
    k.check = [acc, non_empty](const S& s) -> std::string {
      return non_empty && acc(s).empty() ? "must not be empty" : "";
    };
    return add(std::move(k));
  }

  /// Three numbers "x y z" (an Eigen::Vector3d), each within `range`.
  template <class M>
  Section& vector3(std::string key, M member, std::string unit, Range range, std::string doc) {
    auto acc = detail::accessor<S>(member);
    Key k = newKey(std::move(key), std::move(unit), std::move(doc), "x y z, each " + range.text());
    k.set = [acc, range, unit = k.info.unit](std::string_view text, S& s) {
      std::vector<double> v;
      std::string err = parseNumbers(text, 3, v);
      for (std::size_t i = 0; err.empty() && i < 3; ++i)
        if (!range.contains(v[i])) err = detail::outOfRange(formatNumber(v[i]), range, unit);
      if (err.empty()) acc(s) = Eigen::Vector3d(v[0], v[1], v[2]);
      return err;
    };
    k.get = [acc](const S& s) {
      const Eigen::Vector3d& v = acc(s);
      return formatNumber(v.x()) + " " + formatNumber(v.y()) + " " + formatNumber(v.z());
    };
    k.check = [acc, range, unit = k.info.unit](const S& s) -> std::string {
      const Eigen::Vector3d& v = acc(s);
      for (int i = 0; i < 3; ++i)
        if (!range.contains(v[i])) return detail::outOfRange(formatNumber(v[i]), range, unit);
      return "";
    };
    return add(std::move(k));
  }

  /// One of a list of names, each standing for a value of the member.
  template <class M, class T = detail::MemberType<S, M>>
  Section& choice(std::string key, M member, std::vector<std::pair<std::string, T>> choices,
                  std::string doc) {
    auto acc = detail::accessor<S>(member);
    std::string accepted;
    for (const auto& c : choices) accepted += (accepted.empty() ? "" : " | ") + c.first;
    Key k = newKey(std::move(key), "-", std::move(doc), accepted);
    k.set = [acc, choices](std::string_view text, S& s) -> std::string {
      for (const auto& [name, value] : choices)
        if (sameName(name, text)) {
          acc(s) = value;
          return "";
        }
      std::string all;
      for (const auto& c : choices) all += (all.empty() ? "'" : ", '") + c.first + "'";
      return quote(text) + " is not one of " + all;
    };
    k.get = [acc, choices](const S& s) -> std::string {
      for (const auto& [name, value] : choices)
        if (acc(s) == value) return name;
      return "?";
    };
    k.check = [acc, choices](const S& s) -> std::string {
      for (const auto& c : choices)
        if (acc(s) == c.second) return "";
      return "is not one of the accepted values";
    };
    return add(std::move(k));
  }

  /// A value of any other type, with its own parse (returns an error or "") and format.
  template <class M, class T = detail::MemberType<S, M>>
  Section& custom(std::string key, M member, std::string unit, std::string accepted,
                  std::function<std::string(std::string_view, T&)> parse,
                  std::function<std::string(const T&)> format, std::string doc) {
    auto acc = detail::accessor<S>(member);
    Key k = newKey(std::move(key), std::move(unit), std::move(doc), std::move(accepted));
    k.set = [acc, parse](std::string_view text, S& s) {
      T x = acc(s);
      std::string err = parse(text, x);
      if (err.empty()) acc(s) = std::move(x);
      return err;
    };
    k.get = [acc, format](const S& s) { return format(acc(s)); };
    return add(std::move(k));
  }

  /// A family of numbered keys <prefix>1, <prefix>2, ... (documented as "<prefix><k>"): element
  /// k-1 of a std::vector member, read by `parse` and written by `format` (as custom()), checked
  /// by `check` (returns an error or ""; also by validate()). The vector's length is set by the key
  /// `count_key` (declared before, e.g. with custom()); element keys are applied after the
  /// section's other keys whatever their order in the file, and an element key beyond the length
  /// is an error, as is an element the length adds (beyond the struct's before loading) that the
  /// file does not give.
  template <class M, class T = typename detail::MemberType<S, M>::value_type>
  Section& items(std::string prefix, M member, std::string count_key, std::string unit,
                 std::string accepted, std::function<std::string(std::string_view, T&)> parse,
                 std::function<std::string(const T&)> format,
                 std::function<std::string(const T&)> check, std::string doc) {
    auto acc = detail::accessor<S>(member);
    Key k = newKey(prefix + "<k>", std::move(unit), std::move(doc), std::move(accepted));
    Items it;
    it.prefix = std::move(prefix);
    it.count_key = std::move(count_key);
    it.size = [acc](const S& s) { return acc(s).size(); };
    it.set = [acc, parse](std::string_view text, S& s, std::size_t i) {
      T x = acc(s)[i];
      std::string err = parse(text, x);
      if (err.empty()) acc(s)[i] = std::move(x);
      return err;
    };
    it.get = [acc, format](const S& s, std::size_t i) { return format(acc(s)[i]); };
    it.check = [acc, check](const S& s, std::size_t i) { return check(acc(s)[i]); };
    k.items = std::make_shared<Items>(std::move(it));
    return add(std::move(k));
  }

  /// The key declared last is dumped only when `applies` holds for the struct (it is still read
  /// and checked): a key that matters only for some values of others.
  Section& when(std::function<bool(const S&)> applies) {
    keys_.back().applies = std::move(applies);
    return *this;
  }

  /// What reads the keys declared after this call ("joint, paper"; "": not said), unless
  /// readBy() says otherwise for one of them.
  Section& readers(std::string readers) {
    readers_ = std::move(readers);
    return *this;
  }
  /// What reads the key declared last ("joint, paper").
  Section& readBy(std::string readers) {
    keys_.back().info.readers = std::move(readers);
    return *this;
  }
  /// A name the key declared last had in an earlier layout: [section] key (`key` empty: the
  /// same name). It is still read (renameFormerKeys()), with a notice.
  Section& formerly(std::string section, std::string key = "") {
    KeyInfo& k = keys_.back().info;
    k.former.push_back({std::move(section), key.empty() ? k.name : std::move(key)});
    return *this;
  }

  /// A key that is refused with its own message (e.g. a key renamed in an earlier version:
  /// "no longer a key: ..." saying what replaces it).
  Section& refused(std::string key, std::string message) {
    refused_.emplace_back(std::move(key), std::move(message));
    return *this;
  }
  /// Keys another program reads from this section: accepted and ignored.
  Section& foreign(std::vector<std::string> keys) {
    foreign_.insert(foreign_.end(), keys.begin(), keys.end());
    return *this;
  }
  /// A check across keys, run after loading and by validate(); reports with Checker::fail.
  Section& check(std::function<void(const S&, const Checker&)> f) {
    checks_.push_back(std::move(f));
    return *this;
  }

  /// Loads this section of `ini` (if present) into `s`, over its current values. Unknown,
  /// refused and malformed keys, out-of-range values and failed checks throw ConfigError naming
  /// the file, the line, the section and the key.
  void load(const IniFile& ini, S& s) const { load(ini, name_, s); }
  /// The same from a section of another name (e.g. a sensor's section, named by the user).
  void load(const IniFile& ini, const std::string& section, S& s) const {
    if (const IniSection* sec = ini.section(section)) {
      std::vector<std::size_t> sizes;  // of the lists before loading
      for (const Key& k : keys_)
        if (k.items) sizes.push_back(k.items->size(s));
      std::vector<std::pair<const IniEntry*, std::pair<const Key*, std::size_t>>> elements;
      for (const IniEntry& e : sec->entries) {
        std::size_t index = 0;
        if (const Key* k = findItem(e.key, index)) {
          elements.push_back({&e, {k, index}});
          continue;
        }
        const Key* k = find(e.key);
        if (!k) {
          if (isForeign(e.key)) continue;
          for (const auto& [refused, message] : refused_)
            if (sameName(refused, e.key)) ini.fail(section, e.key, message);
          detail::unknownKey(ini, section, e.key, names());
        }
        if (const std::string err = k->set(e.value, s); !err.empty()) ini.fail(section, e.key, err);
      }
      for (const auto& [e, item] : elements) {
        const Items& it = *item.first->items;
        const std::size_t n = it.size(s);
        if (item.second > n)
          ini.fail(section, e->key, "beyond " + it.count_key + " = " + std::to_string(n));
        std::string err = it.set(e->value, s, item.second - 1);
        if (err.empty()) err = it.check(s, item.second - 1);
        if (!err.empty()) ini.fail(section, e->key, err);
      }
      std::size_t list = 0;
      for (const Key& k : keys_) {
        if (!k.items) continue;
        const std::size_t n = k.items->size(s);
        for (std::size_t i = sizes[list++] + 1; i <= n; ++i) {
          const std::string key = k.items->prefix + std::to_string(i);
          if (!sec->find(key))
            ini.fail(section, key,
                     "missing (" + k.items->count_key + " = " + std::to_string(n) + ")");
        }
      }
    }
    const Checker c(&ini, section);
    for (const auto& f : checks_) f(s, c);
  }

  /// The range and cross-key checks on a struct filled in code. Throws ConfigError
  /// "configuration key <section>.<key>: ...".
  void validate(const S& s) const {
    const Checker c(nullptr, name_);
    for (const Key& k : keys_) {
      if (k.check)
        if (const std::string err = k.check(s); !err.empty()) c.fail(k.info.name, err);
      if (k.items)
        for (std::size_t i = 0; i < k.items->size(s); ++i)
          if (const std::string err = k.items->check(s, i); !err.empty())
            c.fail(k.items->prefix + std::to_string(i + 1), err);
    }
    for (const auto& f : checks_) f(s, c);
  }

  /// Writes "[name]" and one documented line per key (each element of a list; not the keys
  /// whose when() does not hold): an INI that loads back to `s` over a struct that agrees with it
  /// on the keys left out.
  void dump(const S& s, std::ostream& out) const {
    dumpHeader(out);
    dumpKeys(s, out);
  }
  /// Only the lines of the keys (no header), e.g. to add keys of another struct to a section.
  void dumpKeys(const S& s, std::ostream& out, bool commented = false) const {
    for (const Key& k : keys_) dumpKey(k, s, out, commented);
  }
  /// One key's line (commented out: shown, not set).
  void dumpKey(const S& s, const std::string& key, std::ostream& out,
               bool commented = false) const {
    if (const Key* k = find(key)) dumpKey(*k, s, out, commented);
  }
  /// "[name]", its doc and what reads its keys (the readers of all its keys, in order).
  void dumpHeader(std::ostream& out) const;

  std::vector<KeyInfo> keys() const override {
    const S defaults{};
    std::vector<KeyInfo> out;
    for (const Key& k : keys_) {
      KeyInfo i = k.info;
      if (!k.items) i.default_value = k.get(defaults);  // a list's elements have none
      out.push_back(std::move(i));
    }
    return out;
  }
  std::string canonical(const std::string& key, const std::string& text,
                        std::string& error) const override {
    const Key* k = find(key);
    if (!k) {
      error = "not a key of [" + name_ + "]";
      return "";
    }
    S x{};
    error = k->set(text, x);
    return error.empty() ? k->get(x) : "";
  }
  /// The value of `key` in `s` as the dump writes it ("" if no such key).
  std::string value(const S& s, const std::string& key) const {
    const Key* k = find(key);
    return k ? k->get(s) : "";
  }

 private:
  struct Items {  ///< a list's element keys
    std::string prefix, count_key;
    std::function<std::size_t(const S&)> size;
    std::function<std::string(std::string_view, S&, std::size_t)> set;  ///< error or ""
    std::function<std::string(const S&, std::size_t)> get;
    std::function<std::string(const S&, std::size_t)> check;  ///< error or ""
  };
  struct Key {
    KeyInfo info;
    std::function<std::string(std::string_view, S&)> set;  ///< returns an error or ""
    std::function<std::string(const S&)> get;              ///< the value as INI text
    std::function<std::string(const S&)> check;            ///< range error or "" (optional)
    std::shared_ptr<const Items> items = nullptr;          ///< a list (then set/get are unset)
    std::function<bool(const S&)> applies = nullptr;       ///< dumped only when it holds
  };
  /// A key without its functions (set, get, ...), readers or former names.
  static Key newKey(std::string name, std::string unit, std::string doc, std::string accepted) {
    Key k;
    k.info.name = std::move(name);
    k.info.unit = std::move(unit);
    k.info.doc = std::move(doc);
    k.info.accepted = std::move(accepted);
    return k;
  }
  Section& add(Key k) {
    k.info.readers = readers_;
    keys_.push_back(std::move(k));
    return *this;
  }
  const Key* find(std::string_view key) const {
    for (const Key& k : keys_)
      if (!k.items && sameName(k.info.name, key)) return &k;
    return nullptr;
  }
  /// The list whose element `key` is (<prefix><k>, k >= 1 without leading zeros), or nullptr.
  const Key* findItem(std::string_view key, std::size_t& index) const {
    for (const Key& k : keys_) {
      if (!k.items) continue;
      const std::string& p = k.items->prefix;
      if (key.size() <= p.size() || !sameName(key.substr(0, p.size()), p)) continue;
      const std::string_view digits = key.substr(p.size());
      if (digits.size() > 9 || digits[0] == '0' ||
          digits.find_first_not_of("0123456789") != std::string_view::npos)
        continue;
      index = std::stoul(std::string(digits));
      return &k;
    }
    return nullptr;
  }
  void dumpKey(const Key& k, const S& s, std::ostream& out, bool commented) const {
    if (k.applies && !k.applies(s)) return;
    if (!k.items) return detail::dumpLine(out, k.info, k.get(s), commented);
    for (std::size_t i = 0; i < k.items->size(s); ++i) {
      KeyInfo element = k.info;
      element.name = k.items->prefix + std::to_string(i + 1);
      detail::dumpLine(out, element, k.items->get(s, i), commented);
    }
  }
  bool isForeign(std::string_view key) const {
    for (const auto& f : foreign_)
      if (sameName(f, key)) return true;
    return false;
  }
  std::vector<std::string> names() const {
    std::vector<std::string> n;
    for (const Key& k : keys_) n.push_back(k.info.name);
    return n;
  }
  std::vector<Key> keys_;
  std::vector<std::function<void(const S&, const Checker&)>> checks_;
  std::string readers_;  ///< of the keys declared next (readers())
};

/// "[name]", "; doc" and "; read by: ..." (the readers of `keys`, each once, in order; none
/// when no key says what reads it).
void dumpSectionHeader(std::ostream& out, const std::string& name, const std::string& doc,
                       const std::vector<KeyInfo>& keys = {});

template <class S>
void Section<S>::dumpHeader(std::ostream& out) const {
  dumpSectionHeader(out, name_, doc_, keys());
}

/// The moves from the earlier layouts that the declarations of `sections` hold (their keys'
/// former names).
std::vector<KeyRename> formerNames(const std::vector<const SectionBase*>& sections);
/// The sections that only former names have: no section of `sections` has their name.
std::vector<std::string> formerSectionNames(const std::vector<const SectionBase*>& sections);
/// `ini` with every key of `sections` given under a former name moved to its current section
/// and name (IniFile::withRenames, formerSectionNames() retired): one notice per such key in
/// `notices`. Throws ConfigError as withRenames does.
IniFile renameFormerKeys(const IniFile& ini, const std::vector<const SectionBase*>& sections,
                         std::vector<std::string>& notices);

}  // namespace freeinit::config
