// The console's feed services, registered the way panel kinds are (static/panels/registry.js): a panel's feed
// {service: "<name>"} names an exchange that is more than a socket read (the drive session, skill goals, the turn
// queue, chat, the camera's binary stream, the map's polling and targets, ...). The module that provides a service
// registers it when it is imported; the console's wiring (console-wiring.js) imports those modules and looks each
// feed up here, so a panel asking for a service nobody registered gets a notice, never a blank.
//
// A service is connect(wiring, descriptor, panel): `wiring` is the console's ConsoleWiring (its public side only:
// robotName, robotPath, root, layout, status, timings, listen(), channel(), hasChannel(), closeChannel(), guard(),
// onStart(), showOnline(), and the events it carries between services, listed in console-wiring.js; limits-service.js
// is the model), `descriptor` the panel's descriptor, `panel` its element. What a service keeps for one console (its
// panels, a poll started once) it keeps with perConsole(), never on the wiring. A new service is a module here that
// calls registerFeedService, imported by console-wiring.js (one line).

const services = new Map();

/** Register a feed service under name; two modules registering one name is a mistake in the code. */
export function registerFeedService(name, connect) {
  if (services.has(name)) throw new Error(`two modules register the feed service "${name}"`);
  if (typeof connect !== "function") throw new Error(`the feed service "${name}" has no connect function`);
  services.set(name, connect);
}

/** The connect function of a registered service, or null. */
export function feedService(name) {
  return services.get(name) ?? null;
}

/** The names of every registered service, sorted. */
export function registeredFeedServices() {
  return [...services.keys()].sort();
}

/** A getter of the state a service module keeps per console: create(wiring) on a console's first use, then the same
 *  object for that console (a page may show two robots' panels, each with its own wiring). */
export function perConsole(create) {
  const states = new WeakMap();
  return (wiring) => {
    if (!states.has(wiring)) states.set(wiring, create(wiring));
    return states.get(wiring);
  };
}
