// The page's one WebSocket (/ws/link) that carries all its channels (middleware/live/link.py says the format).
// Each Channel (transport.js) rides on it as a numbered subscription; the Channel keeps its own backoff, and the
// link connects when a channel needs it.

export class PageLink {
  #url;
  #socket = null;
  #open = false;
  #carriers = new Set(); // every carrier that wants to be subscribed while the socket lives
  #bySub = new Map(); // sub -> carrier
  #nextSub = 1;

  constructor(url) {
    this.#url = url;
  }

  /** Subscribe to path; `on` gets open(), message(data) and close(code, reason), as from a socket of its own. */
  carry(path, on) {
    const carrier = new LinkCarrier(this, path, on);
    this.#carriers.add(carrier);
    if (this.#open) this.#subscribe(carrier);
    else if (!this.#socket) this.#connect();
    return carrier;
  }

  get isOpen() {
    return this.#open;
  }

  send(carrier, text) {
    if (this.#open && carrier.sub) this.#socket.send(`${carrier.sub} ${text}`);
  }

  drop(carrier) {
    this.#carriers.delete(carrier);
    if (carrier.sub && this.#bySub.get(carrier.sub) === carrier) {
      this.#bySub.delete(carrier.sub);
      if (this.#open) this.#socket.send(JSON.stringify({ type: "unsubscribe", sub: carrier.sub }));
    }
  }

  #subscribe(carrier) {
    const sub = this.#nextSub++;
    carrier.sub = sub;
    this.#bySub.set(sub, carrier);
    this.#socket.send(JSON.stringify({ type: "subscribe", sub, path: carrier.path }));
  }

  #connect() {
    const socket = new WebSocket(this.#url);
    socket.binaryType = "arraybuffer";
    this.#socket = socket;
    socket.addEventListener("open", () => {
      this.#open = true;
      for (const carrier of this.#carriers) this.#subscribe(carrier);
    });
    socket.addEventListener("message", (event) => this.#deliver(event.data));
    socket.addEventListener("close", (event) => {
      if (this.#socket !== socket) return;
      this.#socket = null;
      this.#open = false;
      const carriers = [...this.#carriers];
      this.#carriers.clear();
      this.#bySub.clear();
      for (const carrier of carriers) carrier.ended(event.code, event.reason);
    });
  }

  #deliver(data) {
    if (data instanceof ArrayBuffer) {
      if (data.byteLength < 4) return;
      this.#bySub.get(new DataView(data).getUint32(0))?.on.message(data.slice(4));
      return;
    }
    const space = data.indexOf(" ");
    const sub = Number(data.slice(0, space));
    const text = data.slice(space + 1);
    if (sub !== 0) {
      this.#bySub.get(sub)?.on.message(text);
      return;
    }
    let control;
    try {
      control = JSON.parse(text);
    } catch {
      return;
    }
    const carrier = this.#bySub.get(control?.sub);
    if (control?.type === "subscribed") carrier?.opened();
    else if (control?.type === "closed" && carrier) {
      this.#bySub.delete(control.sub);
      this.#carriers.delete(carrier);
      carrier.ended(control.code, control.reason ?? "");
    } else if (control?.type === "error") console.warn("the lab's link refused a message:", control.message);
  }
}

/** One channel's subscription on the link. */
class LinkCarrier {
  sub = null;
  #subscribed = false;
  #done = false;

  constructor(link, path, on) {
    this.link = link;
    this.path = path;
    this.on = on;
  }

  get isOpen() {
    return this.#subscribed && this.link.isOpen;
  }

  send(text) {
    this.link.send(this, text);
  }

  close() {
    this.#done = true;
    this.link.drop(this);
  }

  opened() {
    this.#subscribed = true;
    this.on.open();
  }

  ended(code, reason) {
    this.#subscribed = false;
    this.sub = null;
    if (!this.#done) {
      this.#done = true;
      this.on.close(code, reason);
    }
  }
}
