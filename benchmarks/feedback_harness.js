// Harness of benchmarks/feedback.py, injected as a classic script into a headless Chromium tab served from
// client_ui/static (so the product's ES modules import as they do in the console).
//
// - predictWarp: the product's bookkeeping and transform (the camera panel's FeedbackLayer, hence
//   feedback-math.js's CommandLog and warpTransform, with the laser's depth), drawn by the panel's own
//   drawWarped (edges continued, or black as the thesis), read back for grading.
// - measureCost: time per frame of that warp beside thesisPerPixel, the thesis's per-pixel approach
//   (algorithm 3.1's shift with black fill, and the zoom algorithm 3.2 intends) in a JavaScript loop.
//   thesisPerPixel exists only here, for comparison: the product must not carry it.
(() => {
  const MATH = "/lib/feedback-math.js";
  const PANEL = "/panels/camera-panel/camera-feedback.js";

  function decode(b64) {
    const binary = atob(b64);
    const bytes = new Uint8ClampedArray(binary.length);
    for (let i = 0; i < binary.length; i += 1) bytes[i] = binary.charCodeAt(i);
    return bytes;
  }

  function encode(bytes) {
    let binary = "";
    for (let i = 0; i < bytes.length; i += 0x8000) {
      binary += String.fromCharCode.apply(null, bytes.subarray(i, i + 0x8000));
    }
    return btoa(binary);
  }

  function bitmapFrom(b64, width, height) {
    return createImageBitmap(new ImageData(decode(b64), width, height));
  }

  function canvasOf(width, height) {
    const canvas = document.createElement("canvas");
    canvas.width = width;
    canvas.height = height;
    return canvas;
  }

  /**
   * The thesis's way: draw the frame, getImageData, move every pixel in a JavaScript loop (sideways shift and
   * scale about the vanishing point, nearest neighbour, black where nothing is known), putImageData.
   * `out` is an ImageData reused between frames (kinder to this method than allocating one per frame).
   */
  function thesisPerPixel(ctx, bitmap, t, width, height, out) {
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.drawImage(bitmap, 0, 0, width, height);
    const source = ctx.getImageData(0, 0, width, height).data;
    const target = out.data;
    const inverse = 1 / t.scale;
    for (let y = 0; y < height; y += 1) {
      const sy = Math.floor((y + 0.5 - t.ty) * inverse);
      const rowInside = sy >= 0 && sy < height;
      const row = sy * width;
      for (let x = 0; x < width; x += 1) {
        const o = (y * width + x) * 4;
        const sx = Math.floor((x + 0.5 - t.tx) * inverse);
        if (rowInside && sx >= 0 && sx < width) {
          const i = (row + sx) * 4;
          target[o] = source[i];
          target[o + 1] = source[i + 1];
          target[o + 2] = source[i + 2];
        } else {
          target[o] = 0;
          target[o + 1] = 0;
          target[o + 2] = 0;
        }
        target[o + 3] = 255;
      }
    }
    ctx.putImageData(out, 0, 0);
  }

  /**
   * One moment of a scripted drive: the stale frame warped by the commands it does not show, as the console
   * would draw it when that frame arrives at nowMs, and the same frame warped by the true motion (oracle).
   */
  async function predictWarp({ stale, width, height, hfovDeg, commands, appliedSequence, nowMs, truePose, scan }) {
    const math = await import(MATH);
    const { FeedbackLayer, drawWarped } = await import(PANEL);
    const layer = new FeedbackLayer();
    layer.setInfo({ camera_hfov_deg: hfovDeg, camera_width_px: width, camera_height_px: height });
    layer.setScan(scan);
    layer.reset(0);
    for (const command of commands) layer.recordSent(command.message, command.sentMs);
    layer.recordFrame({ last_applied_sequence: appliedSequence }, nowMs);
    const bitmap = await bitmapFrom(stale, width, height);
    // The real panel draw, on a scratch canvas, yields the transform the console would use now.
    layer.draw(canvasOf(width, height), bitmap, nowMs);
    const transform = layer.lastTransform;
    const canvas = canvasOf(width, height);
    const ctx = canvas.getContext("2d");
    const drawn = (image, t, fill) => {
      drawWarped(ctx, image, t, fill);
      return encode(ctx.getImageData(0, 0, width, height).data);
    };
    const warped = drawn(bitmap, transform, "edges");
    const warpedBlack = drawn(bitmap, transform, "black");
    const depth = Number.isFinite(transform.depthM) ? transform.depthM : undefined;
    const oracleTransform = math.warpTransform(truePose, math.cameraModel({ width, height, hfovDeg }), depth);
    const oracle = drawn(bitmap, oracleTransform, "edges");
    const identity = drawn(bitmap, { shiftX: 0, scale: 1, tx: 0, ty: 0 }, "edges");
    // Where the warped frame shows the stale frame's pixels (white) rather than the fill.
    const white = canvasOf(width, height);
    const whiteCtx = white.getContext("2d");
    whiteCtx.fillStyle = "#fff";
    whiteCtx.fillRect(0, 0, width, height);
    const coverage = drawn(white, transform, "black");
    bitmap.close();
    return {
      warped, warpedBlack, oracle, identity, coverage, depthM: transform.depthM ?? null,
      outstanding: layer.log.outstanding().length,
      transform: { scale: transform.scale, tx: transform.tx, ty: transform.ty, shiftX: transform.shiftX },
      predictedPose: transform.pose,
      oracleTransform,
    };
  }

  function median(values) {
    const sorted = [...values].sort((a, b) => a - b);
    const middle = Math.floor(sorted.length / 2);
    return sorted.length % 2 ? sorted[middle] : (sorted[middle - 1] + sorted[middle]) / 2;
  }

  function percentile(values, q) {
    const sorted = [...values].sort((a, b) => a - b);
    return sorted[Math.min(sorted.length - 1, Math.floor((q / 100) * sorted.length))];
  }

  /**
   * Time per frame of the feedback layer's warp and of the thesis's per-pixel loop, interleaved frame by frame
   * on two canvases so that neighbours' load falls on both alike. Each frame ends with a 1-pixel getImageData,
   * which waits for the drawing to be done (without it, only the submission of canvas commands is timed).
   */
  async function measureCost({ frame, width, height, frames, warmup }) {
    const math = await import(MATH);
    const { drawWarped } = await import(PANEL);
    const bitmap = await bitmapFrom(frame, width, height);
    const camera = math.cameraModel({ width, height });
    const transforms = Array.from({ length: frames + warmup }, (_, i) => {
      const phase = (i % 40) / 40;
      return math.warpTransform({ x_m: 0.1 + 0.4 * phase, y_m: 0.05 * phase, theta_rad: 0.3 * Math.sin(2 * Math.PI * phase) },
        camera);
    });
    const layerCtx = canvasOf(width, height).getContext("2d");
    const blackCtx = canvasOf(width, height).getContext("2d");
    const loopCtx = canvasOf(width, height).getContext("2d");
    const out = loopCtx.createImageData(width, height);
    // The whole panel draw as the console runs it: prediction from 20 outstanding commands (a pose like the sweep above), warp, path.
    const { FeedbackLayer } = await import(PANEL);
    const panel = new FeedbackLayer();
    panel.setInfo({ camera_width_px: width, camera_height_px: height });
    panel.reset(0);
    for (let n = 1; n <= 20; n += 1) {
      panel.recordSent({ type: "drive", sequence: n, linear_mps: 0.25, angular_radps: 0.3 }, n * 50);
    }
    panel.recordFrame({ last_applied_sequence: 0 }, 1000);
    const panelCanvas = canvasOf(width, height);
    const panelCtx = panelCanvas.getContext("2d");
    const layerMs = [];
    const blackMs = [];
    const loopMs = [];
    const panelMs = [];
    for (let i = 0; i < frames + warmup; i += 1) {
      const t = transforms[i];
      let started = performance.now();
      panel.draw(panelCanvas, bitmap, 1000 + (i % 40) * 10);
      panelCtx.getImageData(0, 0, 1, 1);
      const whole = performance.now() - started;
      started = performance.now();
      drawWarped(layerCtx, bitmap, t, "edges");
      layerCtx.getImageData(0, 0, 1, 1);
      const layer = performance.now() - started;
      started = performance.now();
      drawWarped(blackCtx, bitmap, t, "black");
      blackCtx.getImageData(0, 0, 1, 1);
      const black = performance.now() - started;
      started = performance.now();
      thesisPerPixel(loopCtx, bitmap, t, width, height, out);
      loopCtx.getImageData(0, 0, 1, 1);
      const loop = performance.now() - started;
      if (i >= warmup) {
        layerMs.push(layer);
        blackMs.push(black);
        loopMs.push(loop);
        panelMs.push(whole);
      }
    }
    // Both methods on one transform, to check the comparison does the same job (bilinear vs nearest differ a little).
    const check = transforms[0];
    drawWarped(blackCtx, bitmap, check, "black");
    thesisPerPixel(loopCtx, bitmap, check, width, height, out);
    const a = blackCtx.getImageData(0, 0, width, height).data;
    const b = loopCtx.getImageData(0, 0, width, height).data;
    let sum = 0;
    for (let i = 0; i < a.length; i += 4) sum += Math.abs(a[i] - b[i]) + Math.abs(a[i + 1] - b[i + 1]) + Math.abs(a[i + 2] - b[i + 2]);
    bitmap.close();
    const summary = (values) => ({
      median: median(values), p95: percentile(values, 95), mean: values.reduce((s, v) => s + v, 0) / values.length,
    });
    return {
      layer: summary(layerMs), layerBlack: summary(blackMs), perPixel: summary(loopMs), panelDraw: summary(panelMs),
      agreementMae: sum / ((a.length / 4) * 3), frames, crossOriginIsolated: self.crossOriginIsolated,
    };
  }

  window.feedbackBench = { predictWarp, measureCost };
})();
