// The USARSim line grammar as the console reads it: TYPE {Key Value} {Key Value} ...
// A segment is a key and the rest of it as its value; a packed segment
// ({Name F1 Range 5.0}) holds several key-value pairs.

export function parseLine(text) {
  const m = /^\s*([^\s{}]+)/.exec(text);
  const segments = [];
  const re = /\{([^{}]*)\}/g;
  let s;
  while ((s = re.exec(text)) !== null) segments.push(s[1].trim());
  return { type: m ? m[1].toUpperCase() : "", segments };
}

export function splitSegment(body) {
  const i = body.search(/\s/);
  return i < 0 ? [body, ""] : [body.slice(0, i), body.slice(i).trim()];
}

// The first value of each key.
export function fields(text) {
  const out = {};
  for (const body of parseLine(text).segments) {
    const [k, v] = splitSegment(body);
    if (!(k in out)) out[k] = v;
  }
  return out;
}

function packedPairs(tokens) {
  const out = [];
  for (let i = 0; i + 1 < tokens.length; i += 2) out.push([tokens[i], tokens[i + 1]]);
  return out;
}

// A line's segments grouped by item: fields before the first Name, then one entry per
// {Name ...} with the fields that follow it (or that it packs).
export function items(text) {
  const { type, segments } = parseLine(text);
  const head = [];
  const named = [];
  let cur = null;
  for (const body of segments) {
    const tokens = body.split(/\s+/);
    if (tokens[0] === "Name") {
      if (tokens.length > 2 && tokens.length % 2 === 0) {
        cur = { name: tokens[1], fields: packedPairs(tokens.slice(2)) };
      } else {
        cur = { name: splitSegment(body)[1], fields: [] };
      }
      named.push(cur);
      continue;
    }
    const kv = splitSegment(body);
    (cur ? cur.fields : head).push(kv);
  }
  return { type, head, named };
}

export function vec(text) {
  return String(text || "").split(/[\s,]+/).filter((v) => v !== "").map(Number);
}

// A name usable in a protocol segment: no braces, no spaces.
export function cleanName(text) {
  return String(text || "").replace(/[^A-Za-z0-9_.\-]/g, "");
}
