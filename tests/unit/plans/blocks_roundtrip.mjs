// Reads one JSON text a line on stdin and answers one JSON line for each: whether text -> blocks -> text keeps the
// text identical and block -> text -> block the blocks, and the block types used (client_ui's blocks-form.js, the
// mapping the plan page runs, imported as it is). Used by test_plan_blocks_roundtrip.py.
import { createInterface } from "node:readline";
import { pathToFileURL } from "node:url";

const { textToBlocks, blocksToText } = await import(pathToFileURL(process.argv[2]).href);

function types(block, found) {
  for (let current = block; current; current = current.next?.block) {
    found.push(current.type);
    for (const input of Object.values(current.inputs ?? {})) types(input.block, found);
  }
  return found;
}

for await (const line of createInterface({ input: process.stdin })) {
  const text = JSON.parse(line);
  const blocks = textToBlocks(text);
  const back = blocksToText(blocks);
  const again = textToBlocks(back);
  process.stdout.write(JSON.stringify({
    text_kept: back === text, back, blocks_kept: JSON.stringify(again) === JSON.stringify(blocks),
    types: blocks.blocks.blocks.flatMap((top) => types(top, [])),
  }) + "\n");
}
