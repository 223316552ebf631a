// The plan's blocks (Blockly, from the npm registry, pinned in the vendor lock) beside its text: a view of the text,
// never a second plan. Each block is one line (blocks-form.js); an edit of the blocks writes the text, an edit of the
// text redraws the blocks, and Check, Save, Try and Run read the text as they always do, so the checker, the
// prediction and the runs stay one implementation. The server's errors are marked on the block of their line.
//
// Blockly ships UMD builds (its .mjs files re-export them for bundlers), so the page loads blockly_compressed.js and
// msg/en.js as same-origin scripts when the blocks are first shown (CSP script-src 'self': no eval, no inline). Its
// CSS, which it would put in <style> elements the CSP refuses, goes into constructed style sheets instead.
import { blocksToLines, blocksToText, CONDITIONS, EVENTS, SETTINGS, SIDES, textToBlocks } from "./blocks-form.js";
import { t } from "../../lib/i18n.js";

const root = document.getElementById("plan-editor");
const panel = root?.querySelector("[data-slot=blocks]");
const toggle = root?.querySelector("[data-action=show-blocks]");
const text = root?.querySelector("textarea[name=text]");
const errorList = root?.querySelector("[data-slot=errors]");
const SYNC_PERIOD_MS = 300;  // how often the blocks look for a text changed by the page (a version loaded)

const HUES = { motion: 210, control: 120, event: 290, words: 45, raw: 0 };

function loadScript(src) {
  return new Promise((resolve, reject) => {
    const script = document.createElement("script");
    script.src = src;
    script.addEventListener("load", resolve, { once: true });
    script.addEventListener("error", () => reject(new Error(t("{src} did not load.", { src }))), { once: true });
    document.head.append(script);
  });
}

const adopted = new Set();

function adoptCss(cssText) {
  if (!cssText || adopted.has(cssText)) return;
  adopted.add(cssText);
  const sheet = new CSSStyleSheet();
  sheet.replaceSync(cssText);
  document.adoptedStyleSheets = [...document.adoptedStyleSheets, sheet];
}

function installCss(Blockly, media) {
  // Blockly.Css.inject writes its CSS into the root of the element it is given: a shadow root outside the document,
  // whose <style> is never applied (so the CSP has nothing to refuse), read back into a constructed sheet.
  const host = document.createElement("div");
  const probe = document.createElement("div");
  host.attachShadow({ mode: "open" }).append(probe);
  Blockly.Css.inject(probe, true, media);
  adoptCss(probe.getRootNode().querySelector("style")?.textContent ?? "");
  const provider = Blockly.blockRendering.ConstantProvider.prototype;
  provider.injectCSS_ = function injectCss(tagName, selector) { adoptCss(this.getCSS_(selector).join("\n")); };
}

const field = (name, value) => ({ type: "field_input", name, text: value, spellcheck: false });
const choice = (name, values, labels = values) => ({ type: "field_dropdown", name,
  options: values.map((value, index) => [labels[index], value]) });
const holds = () => choice("NOT", ["", "not"], [t("holds"), t("does not hold")]);

function lineBlock(type, message, args, hue, tooltip) {
  return { type, message0: message, args0: args, previousStatement: null, nextStatement: null, colour: hue, tooltip };
}

function definitions() {
  return [
    lineBlock("plan_say", t("say %1"), [field("TEXT", t("hello"))], HUES.words,
      t("A message to the people watching: say \"text\".")),
    lineBlock("plan_drive", t("drive %1 m/s, turn %2 rad/s, for %3"),
      [field("SPEED", "0.2"), field("TURN", "0"), field("TIME", "2s")], HUES.motion,
      t("Wheel velocities held for a time: drive 0.2 0 for 2s.")),
    lineBlock("plan_go_to", t("go to x %1 y %2 %3"), [field("X", "1"), field("Y", "0.5"), field("MORE", "")],
      HUES.motion, t("The go-to-goal skill: go_to 1.2 0.5, then name=value settings such as speed=0.3.")),
    lineBlock("plan_turn_to", t("turn to %1 %2"), [field("HEADING", "90deg"), field("MORE", "")], HUES.motion,
      t("The orientation skill: turn_to 90deg.")),
    lineBlock("plan_follow_wall", t("follow the wall on the %1 %2"),
      [choice("SIDE", SIDES, [t("left"), t("right")]), field("MORE", "0.4 for 20s")], HUES.motion,  // i18n: not prose
      t("The wall-following skill: follow_wall left 0.4 for 20s (distance, then for a time).")),
    lineBlock("plan_skill", t("skill %1 %2"), [field("NAME", "go_to_goal"), field("ARGS", "goal_x_m=1")],
      HUES.motion, t("Any skill of the robot by its name, with name=value parameters.")),
    lineBlock("plan_wait", t("wait %1"), [field("TIME", "1s")], HUES.control, t("Stand still for a time: wait 2s.")),
    lineBlock("plan_wait_until", t("wait until %2 %3 %1, timeout %4"),
      [holds(), choice("COND", CONDITIONS), field("VALUE", "0.5"), field("TIMEOUT", "10s")], HUES.control,
      t("Stand still until the condition holds (or does not): wait_until obstacle_within 0.5 timeout 10s.")),
    lineBlock("plan_set", t("set %1 to %2"), [choice("SETTING", SETTINGS), field("VALUE", "0.3")], HUES.words,
      t("A setting for the rest of the plan: max_speed (m/s), max_turn_rate (rad/s), watchdog (s).")),
    lineBlock("plan_comment", t("# %1"), [field("TEXT", t(" a note"))], HUES.words,
      t("A comment: the robot ignores it.")),
    lineBlock("plan_line", t("line %1"), [field("TEXT", "")], HUES.raw,
      t("A line of the text as it is written: the checker says what it means.")),
    { type: "plan_repeat", message0: t("repeat %1 times"), args0: [field("COUNT", "3")],
      message1: "%1", args1: [{ type: "input_statement", name: "BODY" }], previousStatement: null,
      nextStatement: null, colour: HUES.control, tooltip: t("The blocks inside, this many times: repeat 3 { }.") },
    { type: "plan_if", message0: t("if %2 %3 %1"), args0: [holds(), choice("COND", CONDITIONS), field("VALUE", "0.5")],
      message1: t("then %1"), args1: [{ type: "input_statement", name: "THEN" }], previousStatement: null,
      nextStatement: null, colour: HUES.control, tooltip: t("The blocks inside when the condition holds.") },
    { type: "plan_if_else", message0: t("if %2 %3 %1"),
      args0: [holds(), choice("COND", CONDITIONS), field("VALUE", "0.5")],
      message1: t("then %1"), args1: [{ type: "input_statement", name: "THEN" }],
      message2: t("else %1"), args2: [{ type: "input_statement", name: "ELSE" }], previousStatement: null,
      nextStatement: null, colour: HUES.control, tooltip: t("One block of lines or the other, by the condition.") },
    { type: "plan_on", message0: t("on %1 %2"), args0: [choice("EVENT", EVENTS), field("VALUE", "")],
      message1: t("do %1"), args1: [{ type: "input_statement", name: "BODY" }], previousStatement: null,
      nextStatement: null, colour: HUES.event,
      tooltip: t("When the event happens, the line running is cut short and these blocks run in its place; the " +
        "plan then goes on with the next line. It watches the lines after it in its block.") },
  ];
}

// Categories open a flyout over the workspace, so the blocks keep the column's width (a phone's too).
const category = (name, hue, types) => ({ kind: "category", name, colour: String(hue),
  contents: types.map((type) => ({ kind: "block", type })) });
const TOOLBOX = { kind: "categoryToolbox", contents: [
  category(t("Say and set"), HUES.words, ["plan_say", "plan_set", "plan_comment"]),
  category(t("Move"), HUES.motion, ["plan_drive", "plan_go_to", "plan_turn_to", "plan_follow_wall", "plan_skill"]),
  category(t("Wait and repeat"), HUES.control, ["plan_wait", "plan_wait_until", "plan_repeat", "plan_if",
    "plan_if_else"]),
  category(t("Events"), HUES.event, ["plan_on"]),
] };

class BlocksView {
  constructor(Blockly, area, status, readOnly) {
    this.Blockly = Blockly;
    this.status = status;
    this.workspace = Blockly.inject(area, {
      toolbox: readOnly ? undefined : TOOLBOX, readOnly, sounds: false, css: false, renderer: "geras",
      media: `${panel.dataset.vendor}media/`, trashcan: !readOnly,
      move: { scrollbars: true, drag: true, wheel: false }, zoom: { controls: true, wheel: false, startScale: 0.85 },
    });
    this.synced = null;  // the text the blocks show
    this.loading = false;
    this.workspace.addChangeListener((event) => this.blocksChanged(event));
    this.timer = setInterval(() => this.textChanged(), SYNC_PERIOD_MS);
    new MutationObserver(() => this.markErrors()).observe(errorList, { childList: true, subtree: true });
  }

  save() {
    return this.Blockly.serialization.workspaces.save(this.workspace);
  }

  /** The text changed outside the blocks (typed, a version loaded): the blocks are drawn from it again. */
  textChanged() {
    if (text.value === this.synced) return;
    this.synced = text.value;
    this.loading = true;
    this.Blockly.Events.disable();
    try {
      this.Blockly.serialization.workspaces.load(textToBlocks(text.value), this.workspace);
    } finally {
      this.Blockly.Events.enable();
      this.loading = false;
    }
    this.describe();
    this.markErrors();
  }

  /** A block was added, moved, changed or removed: the text is written from the blocks. */
  blocksChanged(event) {
    if (this.loading || event.isUiEvent) return;
    const written = blocksToText(this.save());
    if (written === text.value) return;
    this.synced = written;
    text.value = written;
    text.dispatchEvent(new Event("input", { bubbles: true }));  // the gutter redraws, the old errors go
    this.describe();
  }

  describe() {
    const count = this.workspace.getAllBlocks(false).length;
    this.status.textContent = t("{count} blocks, one a line of the text above.", { count });
  }

  /** Each error the checker listed is shown on the block of its line (the list holds li[data-line]). */
  markErrors() {
    const { lines } = blocksToLines(this.save());
    const messages = new Map();
    for (const item of errorList.querySelectorAll("li[data-line]")) {
      const id = lines[Number(item.dataset.line) - 1]?.id;
      if (id) messages.set(id, [...(messages.get(id) ?? []), item.textContent.trim()]);
    }
    for (const block of this.workspace.getAllBlocks(false)) {
      block.setWarningText(messages.has(block.id) ? messages.get(block.id).join("\n") : null);
    }
  }
}

let view = null;

async function showBlocks() {
  const opening = panel.hidden;
  panel.hidden = !opening;
  toggle.setAttribute("aria-expanded", String(opening));
  toggle.textContent = opening ? t("Hide the blocks") : t("Edit as blocks");
  if (!opening || view) {
    if (opening) view.Blockly.svgResize(view.workspace);  // drawn while hidden: its size is the panel's now
    return;
  }
  const status = panel.querySelector("[data-field=blocks-status]");
  status.textContent = t("Loading the blocks…");
  try {
    await loadScript(`${panel.dataset.vendor}blockly_compressed.js`);
    await loadScript(`${panel.dataset.vendor}msg/en.js`);
    const { Blockly } = window;
    installCss(Blockly, `${panel.dataset.vendor}media/`);
    Blockly.common.defineBlocksWithJsonArray(definitions());
    view = new BlocksView(Blockly, panel.querySelector("[data-slot=blocks-area]"), status,
      root.dataset.mine !== "true");
    view.textChanged();
    panel.dataset.ready = "true";
  } catch (error) {
    status.textContent = t("The blocks could not be shown: {message} The text editor works as before.",
      { message: error.message });
  }
}

toggle?.addEventListener("click", showBlocks);
if (toggle && new URLSearchParams(location.search).get("blocks") === "1") showBlocks();
