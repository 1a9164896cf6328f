// IDL lexer and recursive-descent parser for the subset rosidl and our interfaces use.
#include "idl_internal.hpp"

namespace unav::introspection {

namespace idl {

std::vector<Token> tokenize(const std::string& text, const std::string& file) {
  std::vector<Token> tokens;
  const size_t n = text.size();
  size_t i = 0;
  int line = 1;
  bool line_start = true;
  while (i < n) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
      line_start = true;
      ++i;
      continue;
    }
    if (std::isspace(static_cast<unsigned char>(c))) {
      ++i;
      continue;
    }
    if (c == '/' && i + 1 < n && text[i + 1] == '/') {
      while (i < n && text[i] != '\n') ++i;
      continue;
    }
    if (c == '/' && i + 1 < n && text[i + 1] == '*') {
      const int start_line = line;
      i += 2;
      while (i < n && !(text[i] == '*' && i + 1 < n && text[i + 1] == '/')) {
        if (text[i] == '\n') ++line;
        ++i;
      }
      if (i >= n) throw IdlError(file, start_line, "unterminated /* comment");
      i += 2;
      continue;
    }
    if (c == '#' && line_start) {
      const size_t end = text.find('\n', i);
      const size_t stop = end == std::string::npos ? n : end;
      tokens.push_back({TokenKind::kDirective, trim(text.substr(i + 1, stop - i - 1)), line});
      i = stop;
      continue;
    }
    line_start = false;
    if (is_ident_start(c)) {
      const size_t b = i;
      while (i < n && is_ident_char(text[i])) ++i;
      tokens.push_back({TokenKind::kIdent, text.substr(b, i - b), line});
      continue;
    }
    if (std::isdigit(static_cast<unsigned char>(c)) ||
        (c == '.' && i + 1 < n && std::isdigit(static_cast<unsigned char>(text[i + 1])))) {
      const size_t b = i;
      const bool hex = c == '0' && i + 1 < n && (text[i + 1] == 'x' || text[i + 1] == 'X');
      while (i < n) {
        const char d = text[i];
        if (is_ident_char(d) || d == '.' ||
            (!hex && (d == '+' || d == '-') && (text[i - 1] == 'e' || text[i - 1] == 'E'))) {
          ++i;
        } else {
          break;
        }
      }
      tokens.push_back({TokenKind::kNumber, text.substr(b, i - b), line});
      continue;
    }
    if (c == '"' || c == '\'') {
      const int start_line = line;
      std::string value;
      ++i;
      while (i < n && text[i] != c) {
        if (text[i] == '\n') throw IdlError(file, start_line, "unterminated literal");
        if (text[i] == '\\' && i + 1 < n) {
          value += unescape_char(text[i + 1]);
          i += 2;
        } else {
          value += text[i++];
        }
      }
      if (i >= n) throw IdlError(file, start_line, "unterminated literal");
      ++i;
      tokens.push_back({c == '"' ? TokenKind::kString : TokenKind::kChar, value, start_line});
      continue;
    }
    if (c == ':' && i + 1 < n && text[i + 1] == ':') {
      tokens.push_back({TokenKind::kPunct, "::", line});
      i += 2;
      continue;
    }
    tokens.push_back({TokenKind::kPunct, std::string(1, c), line});
    ++i;
  }
  tokens.push_back({TokenKind::kEnd, "", line});
  return tokens;
}

namespace {

class Parser {
 public:
  Parser(detail::RegistryState& registry, std::string file, std::string root, std::vector<Token> tokens)
      : registry_(registry), file_(std::move(file)), root_(std::move(root)), tokens_(std::move(tokens)) {}

  std::vector<const StructType*> run() {
    parse_definitions(false);
    return declared_;
  }

 private:
  struct TypeSpec {
    ElementType element;
    Field::Container container = Field::Container::kSingle;
    size_t array_size = 0;
    size_t sequence_bound = 0;
    std::string text;
  };

  [[noreturn]] void fail(int line, const std::string& message) const { throw IdlError(file_, line, message); }

  const Token& peek(size_t k = 0) const { return tokens_[std::min(pos_ + k, tokens_.size() - 1)]; }

  const Token& next() {
    const Token& t = tokens_[pos_];
    if (pos_ + 1 < tokens_.size()) ++pos_;
    return t;
  }

  static std::string describe(const Token& t) {
    switch (t.kind) {
      case TokenKind::kEnd:
        return "end of file";
      case TokenKind::kString:
        return "\"" + t.text + "\"";
      case TokenKind::kDirective:
        return "'#" + t.text + "'";
      default:
        return "'" + t.text + "'";
    }
  }

  bool is_punct(const std::string& p, size_t k = 0) const {
    return peek(k).kind == TokenKind::kPunct && peek(k).text == p;
  }

  bool is_keyword(const std::string& word, size_t k = 0) const {
    return peek(k).kind == TokenKind::kIdent && peek(k).text == word;
  }

  bool accept(const std::string& p) {
    if (!is_punct(p)) return false;
    next();
    return true;
  }

  void expect(const std::string& p, const std::string& context) {
    if (!accept(p)) fail(peek().line, "expected '" + p + "' " + context + ", got " + describe(peek()));
  }

  std::string expect_ident(const std::string& what) {
    if (peek().kind != TokenKind::kIdent) fail(peek().line, "expected " + what + ", got " + describe(peek()));
    return next().text;
  }

  std::string scoped(const std::string& name) const { return scope_.empty() ? name : join(scope_, "::") + "::" + name; }

  // Scoped names `parts` may refer to from the current scope, innermost first.
  std::vector<std::string> lookup_candidates(const std::vector<std::string>& parts, bool absolute) const {
    std::vector<std::string> out;
    const std::string rel = join(parts, "::");
    if (!absolute) {
      for (size_t i = scope_.size(); i > 0; --i) out.push_back(join(scope_, "::", 0, i) + "::" + rel);
    }
    out.push_back(rel);
    return out;
  }

  std::pair<std::vector<std::string>, bool> parse_scoped_name() {
    const bool absolute = accept("::");
    std::vector<std::string> parts{expect_ident("a name")};
    while (is_punct("::")) {
      next();
      parts.push_back(expect_ident("a name after '::'"));
    }
    return {parts, absolute};
  }

  void parse_definitions(bool in_module) {
    while (true) {
      const Token& t = peek();
      if (t.kind == TokenKind::kEnd) {
        if (in_module) fail(t.line, "missing '}' to close module '" + scope_.back() + "'");
        return;
      }
      if (is_punct("}")) {
        if (in_module) return;
        fail(t.line, "unexpected '}'");
      }
      if (t.kind == TokenKind::kDirective) {
        handle_directive(next());
        continue;
      }
      if (accept(";")) continue;
      parse_annotations();  // annotations on modules, structs and typedefs are ignored
      const Token& d = peek();
      if (is_keyword("module")) {
        parse_module();
      } else if (is_keyword("struct")) {
        parse_struct();
      } else if (is_keyword("typedef")) {
        parse_typedef();
      } else if (is_keyword("const")) {
        parse_const();
      } else if (d.kind == TokenKind::kIdent &&
                 (d.text == "enum" || d.text == "union" || d.text == "interface" || d.text == "bitmask" ||
                  d.text == "bitset" || d.text == "exception" || d.text == "valuetype")) {
        fail(d.line, "'" + d.text + "' is not supported");
      } else {
        fail(d.line, "expected module, struct, typedef or const, got " + describe(d));
      }
    }
  }

  void handle_directive(const Token& t) {
    std::istringstream in(t.text);
    std::string word;
    in >> word;
    if (word == "ifndef" || word == "ifdef" || word == "define" || word == "endif" || word == "pragma") {
      return;  // include guards and pragmas; files are parsed once anyway
    }
    if (word != "include") fail(t.line, "unsupported preprocessor directive '#" + word + "'");
    const std::string rest = trim(t.text.substr(7));
    if (rest.size() < 3 ||
        !((rest.front() == '"' && rest.back() == '"') || (rest.front() == '<' && rest.back() == '>'))) {
      fail(t.line, "malformed #include, expected #include \"pkg/msg/Type.idl\"");
    }
    const std::string rel = rest.substr(1, rest.size() - 2);
    std::vector<std::pair<fs::path, std::string>> candidates;
    if (!root_.empty()) candidates.emplace_back(fs::path(root_) / rel, root_);
    for (const std::string& r : registry_.roots) {
      if (r != root_) candidates.emplace_back(fs::path(r) / rel, r);
    }
    candidates.emplace_back(fs::path(file_).parent_path() / rel, std::string());
    for (const auto& [path, root] : candidates) {
      std::error_code ec;
      if (fs::is_regular_file(path, ec)) {
        registry_.parse_file(path, root.empty() ? registry_.root_of(path) : root);
        return;
      }
    }
    std::string searched;
    for (const auto& c : candidates) searched += (searched.empty() ? "" : ", ") + c.first.string();
    fail(t.line, "cannot find included file '" + rel + "' (searched " + searched + ")");
  }

  std::vector<Annotation> parse_annotations() {
    std::vector<Annotation> out;
    while (is_punct("@")) {
      const int line = next().line;
      Annotation a{expect_ident("an annotation name"), {}, line};
      while (is_punct("::")) {
        next();
        a.name += "::" + expect_ident("an annotation name");
      }
      if (accept("(")) {
        int depth = 1;
        while (true) {
          const Token& t = peek();
          if (t.kind == TokenKind::kEnd) fail(line, "unterminated arguments of @" + a.name);
          next();
          if (t.kind == TokenKind::kPunct && t.text == "(") ++depth;
          if (t.kind == TokenKind::kPunct && t.text == ")" && --depth == 0) break;
          a.args.push_back(t);
        }
      }
      out.push_back(std::move(a));
    }
    return out;
  }

  void parse_module() {
    next();
    const std::string name = expect_ident("a module name");
    expect("{", "after 'module " + name + "'");
    scope_.push_back(name);
    parse_definitions(true);
    expect("}", "to close module '" + name + "'");
    scope_.pop_back();
    accept(";");
  }

  void parse_struct() {
    const int line = next().line;
    const std::string name = expect_ident("a struct name");
    if (accept(";")) return;  // forward declaration
    if (is_punct(":")) fail(peek().line, "struct inheritance is not supported");
    expect("{", "after 'struct " + name + "'");
    auto type = std::make_unique<StructType>();
    type->name = scoped(name);
    type->file = file_;
    type->line = line;
    while (!accept("}")) {
      if (peek().kind == TokenKind::kEnd) fail(line, "missing '}' to close struct '" + name + "'");
      if (peek().kind == TokenKind::kDirective) fail(peek().line, "preprocessor directive inside struct");
      parse_member(*type);
    }
    expect(";", "after struct '" + name + "'");
    auto found = registry_.structs.find(type->name);
    if (found == registry_.structs.end()) {
      found = registry_.structs.emplace(type->name, std::move(type)).first;
    }
    declared_.push_back(found->second.get());
  }

  void parse_member(StructType& type) {
    const std::vector<Annotation> annotations = parse_annotations();
    const TypeSpec spec = parse_type_spec();
    while (true) {
      const int line = peek().line;
      Field field;
      field.name = expect_ident("a member name");
      field.type = spec.element;
      field.container = spec.container;
      field.array_size = spec.array_size;
      field.sequence_bound = spec.sequence_bound;
      const std::vector<size_t> dims = parse_dimensions();
      if (dims.size() > 1) fail(line, "multi-dimensional arrays are not supported ('" + field.name + "')");
      if (dims.size() == 1) {
        if (spec.container != Field::Container::kSingle) {
          fail(line, "array of '" + spec.text + "' is not supported ('" + field.name + "')");
        }
        field.container = Field::Container::kArray;
        field.array_size = dims[0];
      }
      for (const Field& f : type.fields) {
        if (f.name == field.name) fail(line, "duplicate member '" + field.name + "'");
      }
      for (const Annotation& a : annotations) {
        if (a.name == "default") field.default_value = default_value(a, field);
      }
      type.fields.push_back(std::move(field));
      if (!accept(",")) break;
    }
    expect(";", "after member");
  }

  std::vector<size_t> parse_dimensions() {
    std::vector<size_t> dims;
    while (accept("[")) {
      dims.push_back(parse_size());
      expect("]", "after array size");
    }
    return dims;
  }

  // `@default (value=X)`: X as a YAML node shaped like the field (a sequence for arrays).
  YAML::Node default_value(const Annotation& a, const Field& field) const {
    std::vector<Token> args = a.args;
    if (args.size() >= 2 && args[0].kind == TokenKind::kIdent && args[0].text == "value" &&
        args[1].kind == TokenKind::kPunct && args[1].text == "=") {
      args.erase(args.begin(), args.begin() + 2);
    }
    if (args.empty()) fail(a.line, "@default needs a value, e.g. @default (value=1.0)");
    std::string text;
    bool is_string = true;
    for (const Token& t : args) {
      if (t.kind != TokenKind::kString && t.kind != TokenKind::kChar) is_string = false;
      text += t.text;
    }
    if (!is_string && (text == "TRUE" || text == "FALSE")) {
      text = text == "TRUE" ? "true" : "false";
    }
    if (field.container == Field::Container::kSingle) return YAML::Node(text);
    const std::string inner = trim(text);
    if (inner.size() < 2 ||
        !((inner.front() == '(' && inner.back() == ')') || (inner.front() == '[' && inner.back() == ']'))) {
      fail(a.line, "@default of array or sequence '" + field.name + "' must look like \"(1, 2)\" or \"[1, 2]\", got '" +
                       text + "'");
    }
    try {
      YAML::Node node = YAML::Load("[" + inner.substr(1, inner.size() - 2) + "]");
      if (node.IsSequence()) return node;
    } catch (const YAML::Exception&) {
    }
    fail(a.line, "cannot parse @default '" + text + "' of '" + field.name + "'");
  }

  size_t parse_size() {
    const Token& t = peek();
    if (t.kind == TokenKind::kNumber) {
      next();
      const auto v = parse_integer_literal(t.text);
      if (!v || *v == 0) fail(t.line, "expected a positive integer size, got '" + t.text + "'");
      return static_cast<size_t>(*v);
    }
    if (t.kind == TokenKind::kIdent || is_punct("::")) {
      const int line = t.line;
      const auto [parts, absolute] = parse_scoped_name();
      for (const std::string& name : lookup_candidates(parts, absolute)) {
        const auto c = registry_.constants.find(name);
        if (c == registry_.constants.end()) continue;
        const auto v = parse_integer_literal(c->second.value);
        if (!v || *v == 0) {
          fail(line, "constant '" + name + "' = '" + c->second.value + "' is not a positive integer size");
        }
        return static_cast<size_t>(*v);
      }
      fail(line, "unknown constant '" + join(parts, "::") + "'");
    }
    fail(t.line, "expected a size (integer or constant), got " + describe(t));
  }

  std::optional<PrimitiveKind> parse_primitive() {
    static const std::map<std::string, PrimitiveKind> kSimple = {
        {"boolean", PrimitiveKind::kBool},  {"octet", PrimitiveKind::kOctet},   {"char", PrimitiveKind::kChar},
        {"int8", PrimitiveKind::kInt8},     {"uint8", PrimitiveKind::kUint8},   {"int16", PrimitiveKind::kInt16},
        {"uint16", PrimitiveKind::kUint16}, {"int32", PrimitiveKind::kInt32},   {"uint32", PrimitiveKind::kUint32},
        {"int64", PrimitiveKind::kInt64},   {"uint64", PrimitiveKind::kUint64}, {"float", PrimitiveKind::kFloat},
        {"double", PrimitiveKind::kDouble}, {"short", PrimitiveKind::kInt16},
    };
    const Token& t = peek();
    if (t.kind != TokenKind::kIdent) return std::nullopt;
    const auto it = kSimple.find(t.text);
    if (it != kSimple.end()) {
      next();
      return it->second;
    }
    if (t.text == "long") {
      next();
      if (is_keyword("long")) {
        next();
        return PrimitiveKind::kInt64;
      }
      if (is_keyword("double")) fail(t.line, "'long double' is not supported");
      return PrimitiveKind::kInt32;
    }
    if (t.text == "unsigned") {
      next();
      if (is_keyword("short")) {
        next();
        return PrimitiveKind::kUint16;
      }
      if (is_keyword("long")) {
        next();
        if (is_keyword("long")) {
          next();
          return PrimitiveKind::kUint64;
        }
        return PrimitiveKind::kUint32;
      }
      fail(t.line, "expected 'short' or 'long' after 'unsigned', got " + describe(peek()));
    }
    if (t.text == "wchar" || t.text == "wstring" || t.text == "fixed" || t.text == "any") {
      fail(t.line, "type '" + t.text + "' is not supported");
    }
    return std::nullopt;
  }

  TypeSpec parse_type_spec() {
    const Token& t = peek();
    TypeSpec spec;
    if (const auto primitive = parse_primitive()) {
      spec.element.kind = ElementType::Kind::kPrimitive;
      spec.element.primitive = *primitive;
      spec.text = primitive_name(*primitive);
      return spec;
    }
    if (is_keyword("string")) {
      next();
      spec.element.kind = ElementType::Kind::kString;
      if (accept("<")) {
        spec.element.string_bound = parse_size();
        expect(">", "after string bound");
      }
      spec.text = element_type_string(spec.element);
      return spec;
    }
    if (is_keyword("sequence")) {
      next();
      expect("<", "after 'sequence'");
      const TypeSpec inner = parse_type_spec();
      if (inner.container != Field::Container::kSingle) {
        fail(t.line, "sequence of '" + inner.text + "' is not supported");
      }
      spec.element = inner.element;
      spec.container = Field::Container::kSequence;
      if (accept(",")) spec.sequence_bound = parse_size();
      expect(">", "to close 'sequence<'");
      spec.text = spec.sequence_bound ? "sequence<" + inner.text + ", " + std::to_string(spec.sequence_bound) + ">"
                                      : "sequence<" + inner.text + ">";
      return spec;
    }
    if (t.kind != TokenKind::kIdent && !is_punct("::")) {
      fail(t.line, "expected a type, got " + describe(t));
    }
    const int line = t.line;
    const auto [parts, absolute] = parse_scoped_name();
    const std::vector<std::string> candidates = lookup_candidates(parts, absolute);
    spec.text = join(parts, "::");
    for (const std::string& name : candidates) {
      const auto alias = registry_.aliases.find(name);
      if (alias != registry_.aliases.end()) {
        spec.element = alias->second.type;
        spec.container = alias->second.container;
        spec.array_size = alias->second.array_size;
        spec.sequence_bound = alias->second.sequence_bound;
        return spec;
      }
      const auto s = registry_.structs.find(name);
      if (s != registry_.structs.end()) {
        spec.element.kind = ElementType::Kind::kStruct;
        spec.element.struct_type = s->second.get();
        return spec;
      }
    }
    for (const std::string& name : candidates) {
      if (const StructType* s = registry_.try_load_by_name(name)) {
        spec.element.kind = ElementType::Kind::kStruct;
        spec.element.struct_type = s;
        return spec;
      }
    }
    fail(line, "unknown type '" + spec.text +
                   "' (not declared before use, not in an included file, "
                   "and no IDL root holds a file declaring it; roots: " +
                   registry_.roots_text() + ")");
  }

  void parse_typedef() {
    next();
    const TypeSpec spec = parse_type_spec();
    const int line = peek().line;
    const std::string name = expect_ident("a typedef name");
    const std::vector<size_t> dims = parse_dimensions();
    expect(";", "after typedef");
    Alias alias{spec.element, spec.container, spec.array_size, spec.sequence_bound};
    if (dims.size() > 1) fail(line, "multi-dimensional arrays are not supported ('" + name + "')");
    if (dims.size() == 1) {
      if (spec.container != Field::Container::kSingle) {
        fail(line, "array of '" + spec.text + "' is not supported ('" + name + "')");
      }
      alias.container = Field::Container::kArray;
      alias.array_size = dims[0];
    }
    registry_.aliases[scoped(name)] = alias;
  }

  void parse_const() {
    next();
    const TypeSpec spec = parse_type_spec();
    const std::string name = expect_ident("a constant name");
    expect("=", "after constant '" + name + "'");
    std::string value;
    while (!is_punct(";")) {
      const Token& t = peek();
      if (t.kind == TokenKind::kEnd || t.kind == TokenKind::kDirective) {
        fail(t.line, "missing ';' after constant '" + name + "'");
      }
      value += next().text;
    }
    next();
    if (value.empty()) fail(peek().line, "constant '" + name + "' has no value");
    registry_.constants[scoped(name)] = Constant{scoped(name), spec.text, value};
  }

  detail::RegistryState& registry_;
  std::string file_;
  std::string root_;
  std::vector<Token> tokens_;
  size_t pos_ = 0;
  std::vector<std::string> scope_;
  std::vector<const StructType*> declared_;
};

}  // namespace

std::vector<const StructType*> parse(detail::RegistryState& registry, const std::string& file, const std::string& root,
                                     std::vector<Token> tokens) {
  return Parser(registry, file, root, std::move(tokens)).run();
}

}  // namespace idl

}  // namespace unav::introspection
