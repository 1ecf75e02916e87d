// Protobuf's JSON mapping, as much of it as the client speaks (docs/http.md): objects, arrays,
// strings, numbers, booleans; 64-bit integers as strings, bytes as base64, doubles that are not
// finite as "NaN"/"Infinity"/"-Infinity". .NET Standard 2.1 has no JSON library of its own
// (System.Text.Json is a package Unity does not carry), and this needs little.
using System;
using System.Collections.Generic;
using System.Globalization;
using System.Text;

namespace Hapticd
{
    /// <summary>A JSON object whose members keep the order they were added in (so a spec always
    /// writes the same text).</summary>
    internal sealed class JsonObject
    {
        internal readonly List<KeyValuePair<string, object>> Members = new List<KeyValuePair<string, object>>();
        private Dictionary<string, object> index_;

        internal JsonObject Add(string name, object value)
        {
            Members.Add(new KeyValuePair<string, object>(name, value));
            index_ = null;
            return this;
        }

        internal object Get(string name)
        {
            if (index_ == null)
            {
                index_ = new Dictionary<string, object>();
                foreach (var m in Members) index_[m.Key] = m.Value;
            }
            object value;
            return index_.TryGetValue(name, out value) ? value : null;
        }

        internal bool Has(string name) { return Get(name) != null; }

        // Typed reads: an absent member is the proto3 default (zero, false, "", empty).
        internal double Double(string name) { return Json.ToDouble(Get(name)); }
        internal ulong U64(string name) { return Json.ToU64(Get(name)); }
        internal uint U32(string name) { return (uint)Json.ToU64(Get(name)); }
        internal bool Bool(string name) { var v = Get(name); return v is bool && (bool)v; }
        internal string String(string name) { return Get(name) as string ?? ""; }
        internal JsonObject Object(string name) { return Get(name) as JsonObject ?? new JsonObject(); }
        internal List<object> Array(string name) { return Get(name) as List<object> ?? new List<object>(); }
    }

    internal static class Json
    {
        // ---- writing ----

        internal static string Write(object value)
        {
            var text = new StringBuilder(256);
            Write(text, value);
            return text.ToString();
        }

        private static void Write(StringBuilder text, object value)
        {
            if (value == null) { text.Append("null"); return; }
            var obj = value as JsonObject;
            if (obj != null)
            {
                text.Append('{');
                for (int i = 0; i < obj.Members.Count; ++i)
                {
                    if (i > 0) text.Append(',');
                    WriteString(text, obj.Members[i].Key);
                    text.Append(':');
                    Write(text, obj.Members[i].Value);
                }
                text.Append('}');
                return;
            }
            var list = value as System.Collections.IList;
            if (list != null && !(value is string))
            {
                text.Append('[');
                for (int i = 0; i < list.Count; ++i)
                {
                    if (i > 0) text.Append(',');
                    Write(text, list[i]);
                }
                text.Append(']');
                return;
            }
            if (value is string) { WriteString(text, (string)value); return; }
            if (value is bool) { text.Append((bool)value ? "true" : "false"); return; }
            if (value is double) { WriteDouble(text, (double)value); return; }
            // 64-bit integers as strings, as protobuf's JSON mapping writes them (a double cannot hold them).
            if (value is ulong || value is long) { text.Append('"').Append(Convert.ToString(value, CultureInfo.InvariantCulture)).Append('"'); return; }
            if (value is uint || value is int) { text.Append(Convert.ToString(value, CultureInfo.InvariantCulture)); return; }
            if (value is byte[]) { text.Append('"').Append(Convert.ToBase64String((byte[])value)).Append('"'); return; }
            throw new ArgumentException("Json: " + value.GetType().Name + " cannot be written");
        }

        /// <summary>The shortest text that reads back as the same double ("R", checked: some
        /// runtimes' "R" does not round-trip; then 17 digits).</summary>
        internal static string DoubleText(double v)
        {
            if (double.IsNaN(v)) return "\"NaN\"";
            if (double.IsPositiveInfinity(v)) return "\"Infinity\"";
            if (double.IsNegativeInfinity(v)) return "\"-Infinity\"";
            string s = v.ToString("R", CultureInfo.InvariantCulture);
            double back;
            if (!double.TryParse(s, NumberStyles.Float, CultureInfo.InvariantCulture, out back) ||
                BitConverter.DoubleToInt64Bits(back) != BitConverter.DoubleToInt64Bits(v))
            {
                s = v.ToString("G17", CultureInfo.InvariantCulture);
            }
            return s;
        }

        private static void WriteDouble(StringBuilder text, double v) { text.Append(DoubleText(v)); }

        private static void WriteString(StringBuilder text, string s)
        {
            text.Append('"');
            foreach (char c in s)
            {
                switch (c)
                {
                    case '"': text.Append("\\\""); break;
                    case '\\': text.Append("\\\\"); break;
                    case '\n': text.Append("\\n"); break;
                    case '\r': text.Append("\\r"); break;
                    case '\t': text.Append("\\t"); break;
                    default:
                        if (c < 0x20) text.Append("\\u").Append(((int)c).ToString("x4"));
                        else text.Append(c);
                        break;
                }
            }
            text.Append('"');
        }

        // ---- reading ----

        /// <summary>Parses a JSON text: JsonObject, List&lt;object&gt;, string, double, bool or
        /// null. Throws FormatException naming the offset of what is wrong.</summary>
        internal static object Parse(string text)
        {
            int at = 0;
            object value = ParseValue(text, ref at, 0);
            SkipSpace(text, ref at);
            if (at != text.Length) throw new FormatException("JSON: unexpected text at offset " + at);
            return value;
        }

        private static void SkipSpace(string s, ref int at)
        {
            while (at < s.Length && (s[at] == ' ' || s[at] == '\t' || s[at] == '\n' || s[at] == '\r')) ++at;
        }

        private static object ParseValue(string s, ref int at, int depth)
        {
            if (depth > 64) throw new FormatException("JSON: nested deeper than 64 at offset " + at);
            SkipSpace(s, ref at);
            if (at >= s.Length) throw new FormatException("JSON: ends early");
            char c = s[at];
            if (c == '{')
            {
                ++at;
                var obj = new JsonObject();
                SkipSpace(s, ref at);
                if (at < s.Length && s[at] == '}') { ++at; return obj; }
                for (;;)
                {
                    SkipSpace(s, ref at);
                    string name = ParseString(s, ref at);
                    SkipSpace(s, ref at);
                    Expect(s, ref at, ':');
                    obj.Add(name, ParseValue(s, ref at, depth + 1));
                    SkipSpace(s, ref at);
                    if (at < s.Length && s[at] == ',') { ++at; continue; }
                    Expect(s, ref at, '}');
                    return obj;
                }
            }
            if (c == '[')
            {
                ++at;
                var list = new List<object>();
                SkipSpace(s, ref at);
                if (at < s.Length && s[at] == ']') { ++at; return list; }
                for (;;)
                {
                    list.Add(ParseValue(s, ref at, depth + 1));
                    SkipSpace(s, ref at);
                    if (at < s.Length && s[at] == ',') { ++at; continue; }
                    Expect(s, ref at, ']');
                    return list;
                }
            }
            if (c == '"') return ParseString(s, ref at);
            if (Word(s, ref at, "true")) return true;
            if (Word(s, ref at, "false")) return false;
            if (Word(s, ref at, "null")) return null;
            int start = at;
            while (at < s.Length && "+-0123456789.eE".IndexOf(s[at]) >= 0) ++at;
            double number;
            if (at == start || !double.TryParse(s.Substring(start, at - start), NumberStyles.Float, CultureInfo.InvariantCulture, out number))
            {
                throw new FormatException("JSON: unexpected character at offset " + start);
            }
            return number;
        }

        private static bool Word(string s, ref int at, string word)
        {
            if (string.CompareOrdinal(s, at, word, 0, word.Length) != 0) return false;
            at += word.Length;
            return true;
        }

        private static void Expect(string s, ref int at, char c)
        {
            if (at >= s.Length || s[at] != c) throw new FormatException("JSON: expected '" + c + "' at offset " + at);
            ++at;
        }

        private static string ParseString(string s, ref int at)
        {
            Expect(s, ref at, '"');
            var text = new StringBuilder();
            while (at < s.Length && s[at] != '"')
            {
                char c = s[at++];
                if (c != '\\') { text.Append(c); continue; }
                if (at >= s.Length) break;
                char e = s[at++];
                switch (e)
                {
                    case 'n': text.Append('\n'); break;
                    case 'r': text.Append('\r'); break;
                    case 't': text.Append('\t'); break;
                    case 'b': text.Append('\b'); break;
                    case 'f': text.Append('\f'); break;
                    case 'u':
                        if (at + 4 > s.Length) throw new FormatException("JSON: short \\u escape at offset " + at);
                        text.Append((char)int.Parse(s.Substring(at, 4), NumberStyles.HexNumber, CultureInfo.InvariantCulture));
                        at += 4;
                        break;
                    default: text.Append(e); break;  // \" \\ \/
                }
            }
            Expect(s, ref at, '"');
            return text.ToString();
        }

        // ---- values as proto3 reads them ----

        internal static double ToDouble(object v)
        {
            if (v is double) return (double)v;
            var s = v as string;
            if (s == null) return 0.0;
            if (s == "NaN") return double.NaN;
            if (s == "Infinity") return double.PositiveInfinity;
            if (s == "-Infinity") return double.NegativeInfinity;
            return double.Parse(s, NumberStyles.Float, CultureInfo.InvariantCulture);
        }

        internal static ulong ToU64(object v)
        {
            if (v is double) return (ulong)(double)v;
            var s = v as string;
            return s == null ? 0UL : ulong.Parse(s, CultureInfo.InvariantCulture);
        }
    }
}
