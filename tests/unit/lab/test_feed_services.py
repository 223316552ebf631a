"""The console's feed services register themselves (static/lib/console/feed-services.js), as panel kinds do: every
service a registered panel's feeds name is registered once the console's wiring is imported, and no name twice."""

from __future__ import annotations

THREE_IMPORT_MAP = """
    const map = document.createElement('script');
    map.type = 'importmap';
    map.textContent = JSON.stringify({ imports: { three: '/vendor/node_modules/three/build/three.module.js',
                                                  'three/addons/': '/vendor/node_modules/three/examples/jsm/' } });
    document.head.append(map);
"""


def test_every_service_a_panel_feeds_on_is_registered_by_the_console_s_modules(module_page) -> None:
    module_page.evaluate(f"() => {{ {THREE_IMPORT_MAP} }}")  # the 3D lab view imports three, as pages map it
    result = module_page.evaluate("""async () => {
        const { loadPanels } = await import('/panels/registry.js');
        await import('/lib/console/console-wiring.js');
        const { registeredFeedServices } = await import('/lib/console/feed-services.js');
        const { panels, failed } = await loadPanels();
        const wanted = [...panels.values()].flatMap((p) => p.feeds).filter((f) => f.service).map((f) => f.service);
        return { wanted: [...new Set(wanted)].sort(), registered: registeredFeedServices(), failed };
    }""")
    assert result["failed"] == []
    assert result["wanted"] and set(result["wanted"]) <= set(result["registered"]), result
    assert "chat" in result["registered"], "chat-session.js registers its own service"


def test_a_service_registered_twice_is_refused_and_a_new_one_is_found_by_the_wiring(module_page) -> None:
    result = module_page.evaluate("""async () => {
        const services = await import('/lib/console/feed-services.js');
        const { ConsoleWiring } = await import('/lib/console/console-wiring.js');
        let twice = '';
        try { services.registerFeedService('chat', () => {}); } catch (error) { twice = error.message; }
        const seen = [];
        services.registerFeedService('bumper-history', (wiring, descriptor, panel) => {
            seen.push([wiring.robotName, wiring.robotPath, descriptor.id, panel.tagName]);
        });
        const status = { update() {} };
        const wiring = new ConsoleWiring({ root: document.body, robotName: 'lab-9', robotPath: '/ws/robots/lab-9',
                                           status, layout: {} });
        wiring.wire({ id: 'bumpers' }, document.createElement('div'), [{ service: 'bumper-history' }]);
        let unknown = '';
        try { wiring.wire({ id: 'x' }, document.createElement('div'), [{ service: 'nobody' }]); }
        catch (error) { unknown = error.message; }
        return { twice, seen, unknown };
    }""")
    assert "two modules register the feed service \"chat\"" in result["twice"]
    assert result["seen"] == [["lab-9", "/ws/robots/lab-9", "bumpers", "DIV"]]
    assert "is not one this console offers" in result["unknown"]


def test_a_service_in_its_own_module_registers_itself_when_imported(module_page) -> None:
    registered = module_page.evaluate("""async () => {
        await import('/lib/console/limits-service.js');
        await import('/lib/console/chat-session.js');
        return (await import('/lib/console/feed-services.js')).registeredFeedServices();
    }""")
    assert registered == ["chat", "limits"]
