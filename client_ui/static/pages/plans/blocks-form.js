// The plan's blocks as a view of its text: each line of the text is one block (a repeat, if or on block holds the
// blocks of its lines), read from the text and written back. Pure: no DOM, no Blockly; the state is Blockly's JSON
// serialization (serialization.workspaces.save/load), so the page and node's tests share this one mapping.
//
// The round trip keeps the text IDENTICAL: a line is written back from its block's fields and must come out as it
// was written, else it stays a "line" block holding its text as written. What the fields cannot hold (an
// indentation of one's own, blank lines before a line, a comment after a command, the lines closing a block) goes
// into the block's data, and comes back as it was while the block stands at the depth it was read at. Text whose
// braces do not pair into blocks becomes one "line" block a line. Nothing here checks a plan: the server's checker
// does (POST /api/plans/check), and names the line, which the page marks on its block.

export const INDENT = "  ";
export const CONDITIONS = ["obstacle_within", "goal_reached", "battery_below", "line_seen"];
export const SETTINGS = ["max_speed", "max_turn_rate", "watchdog"];
export const EVENTS = ["obstacle_detected", "wall_lost", "goal_reached", "localized", "battery_low"];
export const SIDES = ["left", "right"];
const KEYWORDS = new Set(["drive", "wait", "wait_until", "repeat", "if", "else", "on", "set", "say", "go_to",
  "turn_to", "follow_wall", "not", "for", "timeout", "true", "false"]);
const WORD = /^[A-Za-z_][A-Za-z0-9_]*$/;

// The fields of each block type, in order, and the statement inputs of the blocks that hold others.
export const BLOCK_FIELDS = {
  plan_say: ["TEXT"],
  plan_drive: ["SPEED", "TURN", "TIME"],
  plan_wait: ["TIME"],
  plan_wait_until: ["NOT", "COND", "VALUE", "TIMEOUT"],
  plan_set: ["SETTING", "VALUE"],
  plan_go_to: ["X", "Y", "MORE"],
  plan_turn_to: ["HEADING", "MORE"],
  plan_follow_wall: ["SIDE", "MORE"],
  plan_skill: ["NAME", "ARGS"],
  plan_comment: ["TEXT"],
  plan_line: ["TEXT"],
  plan_repeat: ["COUNT"],
  plan_if: ["NOT", "COND", "VALUE"],
  plan_if_else: ["NOT", "COND", "VALUE"],
  plan_on: ["EVENT", "VALUE"],
};
export const BLOCK_INPUTS = { plan_repeat: ["BODY"], plan_if: ["THEN"], plan_if_else: ["THEN", "ELSE"],
  plan_on: ["BODY"] };

class Unstructured extends Error {}

const joined = (...words) => words.filter((word) => word !== "").join(" ");

function quoted(text) {
  return `"${text.replace(/\\/g, "\\\\").replace(/"/g, '\\"')}"`;
}

function unquoted(written) {
  if (written.length < 2 || !written.startsWith('"') || !written.endsWith('"')) return null;
  let text = "";
  for (let i = 1; i < written.length - 1; i += 1) {
    const character = written[i];
    if (character === "\\") {
      const next = written[i + 1];
      if (next !== '"' && next !== "\\") return null;
      text += next;
      i += 1;
    } else if (character === '"') {
      return null;
    } else {
      text += character;
    }
  }
  return text;
}

function conditionWords(fields) {
  return joined(fields.NOT, fields.COND, fields.VALUE);
}

/** The line a block stands for, without its indentation (a block holding others: its opening line). */
export function blockLine(type, fields) {
  switch (type) {
    case "plan_say": return `say ${quoted(fields.TEXT)}`;
    case "plan_drive": return joined("drive", fields.SPEED, fields.TURN, "for", fields.TIME);
    case "plan_wait": return joined("wait", fields.TIME);
    case "plan_wait_until":
      return joined("wait_until", conditionWords(fields), fields.TIMEOUT ? `timeout ${fields.TIMEOUT}` : "");
    case "plan_set": return joined("set", fields.SETTING, fields.VALUE);
    case "plan_go_to": return joined("go_to", fields.X, fields.Y, fields.MORE);
    case "plan_turn_to": return joined("turn_to", fields.HEADING, fields.MORE);
    case "plan_follow_wall": return joined("follow_wall", fields.SIDE, fields.MORE);
    case "plan_skill": return joined(fields.NAME, fields.ARGS);
    case "plan_comment": return `#${fields.TEXT}`;
    case "plan_repeat": return joined("repeat", fields.COUNT, "{");
    case "plan_if":
    case "plan_if_else": return joined("if", conditionWords(fields), "{");
    case "plan_on": return joined("on", fields.EVENT, fields.VALUE, "{");
    default: return fields.TEXT ?? "";
  }
}

function condition(words) {
  const negated = words[0] === "not";
  const rest = negated ? words.slice(1) : words;
  if (!CONDITIONS.includes(rest[0]) || rest.length > 2) return null;
  return { NOT: negated ? "not" : "", COND: rest[0], VALUE: rest[1] ?? "" };
}

/** The block of one simple line (its code: no indentation, no comment after it), or null. */
function simpleBlock(code) {
  const words = code.split(" ");
  const [head, ...rest] = words;
  if (head === "say") {
    const text = unquoted(code.slice(4));
    return text === null ? null : { type: "plan_say", fields: { TEXT: text } };
  }
  if (head === "drive" && rest.length === 4 && rest[2] === "for") {
    return { type: "plan_drive", fields: { SPEED: rest[0], TURN: rest[1], TIME: rest[3] } };
  }
  if (head === "wait" && rest.length === 1) return { type: "plan_wait", fields: { TIME: rest[0] } };
  if (head === "wait_until") {
    const at = rest.indexOf("timeout");
    const found = condition(at < 0 ? rest : rest.slice(0, at));
    if (!found || (at >= 0 && at !== rest.length - 2)) return null;
    return { type: "plan_wait_until", fields: { ...found, TIMEOUT: at < 0 ? "" : rest[at + 1] } };
  }
  if (head === "set" && rest.length === 2 && SETTINGS.includes(rest[0])) {
    return { type: "plan_set", fields: { SETTING: rest[0], VALUE: rest[1] } };
  }
  if (head === "go_to" && rest.length >= 2) {
    return { type: "plan_go_to", fields: { X: rest[0], Y: rest[1], MORE: rest.slice(2).join(" ") } };
  }
  if (head === "turn_to" && rest.length >= 1) {
    return { type: "plan_turn_to", fields: { HEADING: rest[0], MORE: rest.slice(1).join(" ") } };
  }
  if (head === "follow_wall" && SIDES.includes(rest[0])) {
    return { type: "plan_follow_wall", fields: { SIDE: rest[0], MORE: rest.slice(1).join(" ") } };
  }
  if (WORD.test(head) && !KEYWORDS.has(head)) {
    return { type: "plan_skill", fields: { NAME: head, ARGS: rest.join(" ") } };
  }
  return null;
}

/** The block opening a block of lines (code ends with " {"), or null. */
function headerBlock(code) {
  const words = code.split(" ");
  if (words.pop() !== "{") return null;
  const [head, ...rest] = words;
  if (head === "repeat" && rest.length === 1) return { type: "plan_repeat", fields: { COUNT: rest[0] } };
  if (head === "if") {
    const found = condition(rest);
    return found ? { type: "plan_if", fields: found } : null;
  }
  if (head === "on" && EVENTS.includes(rest[0]) && rest.length <= 2) {
    return { type: "plan_on", fields: { EVENT: rest[0], VALUE: rest[1] ?? "" } };
  }
  return null;
}

/** [code, what follows it]: the command without a comment after it and without trailing spaces. */
function splitCode(content) {
  let inText = false;
  let end = content.length;
  for (let i = 0; i < content.length; i += 1) {
    const character = content[i];
    if (inText && character === "\\") { i += 1; continue; }
    if (character === '"') inText = !inText;
    if (!inText && character === "#") { end = i; break; }
  }
  let codeEnd = end;
  while (codeEnd > 0 && (content[codeEnd - 1] === " " || content[codeEnd - 1] === "\t")) codeEnd -= 1;
  return [content.slice(0, codeEnd), content.slice(codeEnd)];
}

function hasBraceOutsideText(code) {
  let inText = false;
  for (let i = 0; i < code.length; i += 1) {
    if (inText && code[i] === "\\") { i += 1; continue; }
    if (code[i] === '"') inText = !inText;
    if (!inText && (code[i] === "{" || code[i] === "}")) return true;
  }
  return false;
}

function lineBlock(content) {
  const [code, suffix] = splitCode(content);
  if (code === "") return { block: { type: "plan_comment", fields: { TEXT: content.slice(1) } }, suffix: "" };
  const found = simpleBlock(code);
  if (found && blockLine(found.type, found.fields) === code) return { block: found, suffix };
  return { block: { type: "plan_line", fields: { TEXT: code } }, suffix };
}

function completeFields(block) {
  const fields = {};
  for (const name of BLOCK_FIELDS[block.type]) fields[name] = block.fields[name] ?? "";
  return fields;
}

function leading(line) {
  let end = 0;
  while (end < line.length && (line[end] === " " || line[end] === "\t")) end += 1;
  return [line.slice(0, end), line.slice(end)];
}

/** A block as Blockly's JSON: type, fields, then data (JSON text) when something could not go in its fields. */
function made(type, fields, data) {
  const block = { type, fields: completeFields({ type, fields }) };
  if (Object.keys(data).length) block.data = JSON.stringify(data);
  return block;
}

function note(data, key, value, unless) {
  if (value !== unless) data[key] = value;
}

function chain(blocks) {
  for (let i = 0; i < blocks.length - 1; i += 1) blocks[i].next = { block: blocks[i + 1] };
  return blocks[0] ?? null;
}

function structured(lines) {
  const top = { container: null, items: [], data: null, inputs: null };
  const stack = [top];
  let blank = [];
  for (const line of lines) {
    const [indent, content] = leading(line);
    if (content === "") { blank.push(line); continue; }
    const depth = stack.length - 1;
    const [code] = splitCode(content);
    const frame = stack[stack.length - 1];
    if (code === "}" || code === "} else {") {
      if (!frame.container) throw new Unstructured();
      const closing = code === "}";
      if (!closing && (frame.container.type !== "plan_if" || frame.input !== "THEN")) throw new Unstructured();
      const canonical = INDENT.repeat(depth - 1) + code;
      note(frame.data, closing ? "c" : "e", line, canonical);
      if (blank.length) frame.data[closing ? "cb" : "eb"] = blank;
      blank = [];
      frame.inputs[frame.input] = chain(frame.items);
      if (closing) {
        stack.pop();
        finish(frame);
      } else {
        frame.container.type = "plan_if_else";
        Object.assign(frame, { input: "ELSE", items: [] });
      }
      continue;
    }
    const data = {};
    if (blank.length) data.b = blank;
    blank = [];
    note(data, "i", indent, INDENT.repeat(depth));
    if (code.endsWith("{") && hasBraceOutsideText(code)) {
      const header = headerBlock(code);
      if (!header || blockLine(header.type, header.fields) !== code) throw new Unstructured();
      note(data, "s", content.slice(code.length), "");
      const container = { type: header.type, fields: header.fields };
      const opened = { container, items: [], data, inputs: {}, input: BLOCK_INPUTS[header.type][0], depth };
      frame.items.push(opened);  // placed now, finished when its } comes
      stack.push(opened);
      continue;
    }
    if (hasBraceOutsideText(code)) throw new Unstructured();
    const { block, suffix } = lineBlock(content);
    note(data, "s", suffix, "");
    frame.items.push(made(block.type, block.fields, withDepth(data, depth)));
  }
  if (stack.length > 1) throw new Unstructured();
  return { items: top.items, blank };
}

function withDepth(data, depth) {
  return Object.keys(data).length ? { ...data, d: depth } : data;
}

// A container's frame becomes its block in place (its parent's list holds the frame until then).
function finish(frame) {
  const block = made(frame.container.type, frame.container.fields, withDepth(frame.data, frame.depth));
  const inputs = {};
  for (const name of BLOCK_INPUTS[block.type]) {
    const first = frame.inputs[name] ?? null;
    if (first) inputs[name] = { block: first };
  }
  if (Object.keys(inputs).length) block.inputs = inputs;
  for (const key of Object.keys(frame)) delete frame[key];
  Object.assign(frame, block);
}

function flat(lines) {
  const items = [];
  let blank = [];
  for (const line of lines) {
    const [indent, content] = leading(line);
    if (content === "") { blank.push(line); continue; }
    const data = {};
    if (blank.length) data.b = blank;
    blank = [];
    note(data, "i", indent, "");
    const [code] = splitCode(content);
    const { block, suffix } = hasBraceOutsideText(code)
      ? { block: { type: "plan_line", fields: { TEXT: code } }, suffix: content.slice(code.length) }
      : lineBlock(content);
    note(data, "s", suffix, "");
    items.push(made(block.type, block.fields, withDepth(data, 0)));
  }
  return { items, blank };
}

/** The blocks of a plan's text, as Blockly's workspace JSON. */
export function textToBlocks(text) {
  const lines = text.split("\n");
  const finalNewline = lines.length > 1 && lines[lines.length - 1] === "";
  if (finalNewline || lines[lines.length - 1] === "") lines.pop();
  let read;
  try {
    read = structured(lines);
  } catch (error) {
    if (!(error instanceof Unstructured)) throw error;
    read = flat(lines);
  }
  const { items } = read;
  let { blank } = read;
  if (!items.length && blank.length) {  // only blank lines: the last one is an empty line block
    const data = { ...(blank.length > 1 ? { b: blank.slice(0, -1) } : {}), i: blank[blank.length - 1], d: 0 };
    items.push(made("plan_line", { TEXT: "" }, data));
    blank = [];
  }
  const last = items[items.length - 1];
  if (last && (blank.length || !finalNewline)) {
    const data = last.data ? JSON.parse(last.data) : {};
    if (blank.length) data.t = blank;
    if (!finalNewline) data.nf = true;
    last.data = JSON.stringify(data);
  }
  const first = chain(items);
  return { blocks: { languageVersion: 0, blocks: first ? [{ ...first, x: 16, y: 16 }] : [] } };
}

function dataOf(block) {
  try {
    return block.data ? JSON.parse(block.data) : {};
  } catch {
    return {};  // a block's data the page did not write: as if there were none
  }
}

function emit(block, depth, out) {
  for (let current = block; current; current = current.next?.block) {
    const data = dataOf(current);
    const same = data.d === depth;  // the depth it was read at: its own indentation and closing lines hold
    const fields = completeFields({ type: current.type, fields: current.fields ?? {} });
    for (const line of data.b ?? []) out.push({ text: line, id: current.id ?? null });
    const indent = same && data.i !== undefined ? data.i : INDENT.repeat(depth);
    out.push({ text: indent + blockLine(current.type, fields) + (data.s ?? ""), id: current.id ?? null });
    const inputs = BLOCK_INPUTS[current.type];
    if (!inputs) continue;
    emit(current.inputs?.[inputs[0]]?.block, depth + 1, out);
    if (current.type === "plan_if_else") {
      for (const line of data.eb ?? []) out.push({ text: line, id: current.id ?? null });
      out.push({ text: same && data.e !== undefined ? data.e : `${INDENT.repeat(depth)}} else {`,
        id: current.id ?? null });
      emit(current.inputs?.ELSE?.block, depth + 1, out);
    }
    for (const line of data.cb ?? []) out.push({ text: line, id: current.id ?? null });
    out.push({ text: same && data.c !== undefined ? data.c : `${INDENT.repeat(depth)}}`, id: current.id ?? null });
  }
}

function lastOf(block) {
  let current = block;
  while (current?.next?.block) current = current.next.block;
  return current;
}

/** The text's lines with the id of the block each comes from (the page marks an error's line on its block). */
export function blocksToLines(state) {
  const tops = [...(state?.blocks?.blocks ?? [])];
  tops.sort((a, b) => (a.y ?? 0) - (b.y ?? 0) || (a.x ?? 0) - (b.x ?? 0));
  const out = [];
  for (const top of tops) emit(top, 0, out);
  const data = dataOf(lastOf(tops[tops.length - 1]) ?? {});
  for (const line of data.t ?? []) out.push({ text: line, id: null });
  return { lines: out, finalNewline: !data.nf };
}

/** The plan's text from its blocks. */
export function blocksToText(state) {
  const { lines, finalNewline } = blocksToLines(state);
  if (!lines.length) return "";
  return lines.map((line) => line.text).join("\n") + (finalNewline ? "\n" : "");
}
