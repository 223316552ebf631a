// Draws a run's true path on the lab's map: the walls and obstacles the robot reports, the start, the path.
const PADDING_PX = 12;

/** The map's bounds [x0, y0, x1, y1] around the boxes and the path. */
export function mapBounds(boxes, trace) {
  const xs = [], ys = [];
  for (const box of boxes) {
    const c = Math.abs(Math.cos(box.yaw)), s = Math.abs(Math.sin(box.yaw));
    const rx = box.hx * c + box.hy * s, ry = box.hx * s + box.hy * c;  // the rotated box's half extents
    xs.push(box.x - rx, box.x + rx);
    ys.push(box.y - ry, box.y + ry);
  }
  for (const [, x, y] of trace) { xs.push(x); ys.push(y); }
  if (!xs.length) return [-4, -3, 4, 3];
  return [Math.min(...xs), Math.min(...ys), Math.max(...xs), Math.max(...ys)];
}

/** The line of tape a follow_line rubric measures (a rounded rectangle), drawn under the path. */
function drawLine(context, toPx, scale, rubric) {
  if (rubric?.kind !== "follow_line") return;
  const r = rubric.corner_radius_m;
  const [left, top] = toPx(rubric.x_min_m, rubric.y_max_m);
  context.strokeStyle = "#26272b";
  context.lineWidth = Math.max(2, 0.04 * scale);
  context.beginPath();
  context.roundRect(left, top, (rubric.x_max_m - rubric.x_min_m) * scale, (rubric.y_max_m - rubric.y_min_m) * scale, r * scale);
  context.stroke();
}

export function drawTrace(canvas, boxes, trace, start, rubric = null) {
  const context = canvas.getContext("2d");
  const [x0, y0, x1, y1] = mapBounds(boxes, trace);
  const scale = Math.min((canvas.width - 2 * PADDING_PX) / (x1 - x0 || 1), (canvas.height - 2 * PADDING_PX) / (y1 - y0 || 1));
  const toPx = (x, y) => [PADDING_PX + (x - x0) * scale, canvas.height - PADDING_PX - (y - y0) * scale];
  context.clearRect(0, 0, canvas.width, canvas.height);
  context.fillStyle = "#5b6675";
  for (const box of boxes) {
    const [cx, cy] = toPx(box.x, box.y);
    context.save();
    context.translate(cx, cy);
    context.rotate(-box.yaw);
    context.fillRect(-box.hx * scale, -box.hy * scale, 2 * box.hx * scale, 2 * box.hy * scale);
    context.restore();
  }
  drawLine(context, toPx, scale, rubric);
  if (trace.length) {
    context.strokeStyle = "#1d5fc4";
    context.lineWidth = 2;
    context.beginPath();
    trace.forEach(([, x, y], i) => { const [px, py] = toPx(x, y); if (i) context.lineTo(px, py); else context.moveTo(px, py); });
    context.stroke();
    const [ex, ey] = toPx(trace.at(-1)[1], trace.at(-1)[2]);
    context.fillStyle = "#b1261b";
    context.beginPath();
    context.arc(ex, ey, 5, 0, 2 * Math.PI);
    context.fill();
  }
  if (start) {
    const [sx, sy] = toPx(start[0], start[1]);
    context.strokeStyle = "#17703a";
    context.lineWidth = 3;
    context.beginPath();
    context.arc(sx, sy, 6, 0, 2 * Math.PI);
    context.moveTo(sx, sy);
    context.lineTo(sx + 14 * Math.cos(start[2]), sy - 14 * Math.sin(start[2]));
    context.stroke();
  }
}
