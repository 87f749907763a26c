//! Work a loop cap cuts short is reported, never rendered as less work: an item whose loop
//! hits the engine's iteration cap, and persistent threads a driver stops early (llvmpipe
//! ends every loop of an invocation after 65535 iterations in all), fail the frame with an
//! error naming the layout and the limit. Persistent threads on such a driver take fair
//! shares of the items, so that ordinary work stays below the cap whatever the CPU's load.

use crate::common::{data, gpu};
use lightgraph_engine::{ConstValue, Graph, Instance, Layer, Specialization, compile};
use std::collections::BTreeMap;

/// Runs one frame of the test graph spin.ron in `layout` with `constants`, with subgroup
/// operations where the adapter has them or without (`portable`): the items that finished, or
/// the frame's error.
fn spin_on(layout: &str, constants: &[(&str, u32)], portable: bool) -> Result<u32, String> {
    let vfs = lightgraph::assets::builtin().with_front(Layer::Dir(data("")));
    let graph = Graph::load(&vfs, "graphs/spin.ron").unwrap();
    let spec = Specialization {
        constants: constants
            .iter()
            .map(|(k, v)| (k.to_string(), ConstValue::U32(*v)))
            .collect(),
        flags: Default::default(),
    };
    let target = match portable {
        true => gpu().target().without_subgroups(),
        false => gpu().target(),
    };
    let program = compile(&graph, layout, &graph.layouts[layout], &spec, &target).unwrap();
    let mut instance = Instance::new(gpu(), program, &BTreeMap::new()).unwrap();
    instance.run_frame(0, 1).map_err(|e| e.to_string())?;
    let done = instance.read("done").unwrap();
    Ok(u32::from_le_bytes(done[..4].try_into().unwrap()))
}

/// [`spin_on`] with the adapter's subgroup operations.
fn spin(layout: &str, constants: &[(&str, u32)]) -> Result<u32, String> {
    spin_on(layout, constants, false)
}

#[test]
fn a_loop_that_never_ends_its_item_fails_the_frame() {
    // STEPS far beyond the engine's cap on an item's loop iterations: every item is stopped.
    let err = spin("thread_per_item", &[("ITEMS", 4), ("STEPS", 1 << 24)]).unwrap_err();
    assert!(
        err.contains("layout 'thread_per_item'") && err.contains("items stopped at the cap"),
        "{err}"
    );
    // The same items with an end: each counted once.
    assert_eq!(spin("thread_per_item", &[("ITEMS", 4), ("STEPS", 3)]), Ok(4));
}

#[test]
fn persistent_threads_take_every_item_or_report_the_driver_cap() {
    // The threads are counted with subgroup sums where the adapter has them, one atomic a
    // thread without: both ways.
    for portable in [false, true] {
        // 64 threads over 250 items: shares of 4, the last thread's 2 (fair shares on
        // llvmpipe, any split elsewhere); every item is counted once.
        assert_eq!(
            spin_on("persistent", &[("ITEMS", 250), ("SPIN", 100)], portable),
            Ok(250)
        );
        // 4 items of 30,000 inner iterations each a thread: past llvmpipe's 65,535 iterations
        // an invocation, whose loops then end early. There the frame fails naming the layout
        // and the cap; a driver without the cap counts every item.
        let result = spin_on("persistent", &[("ITEMS", 256), ("SPIN", 30_000)], portable);
        if gpu().caps_invocation_loops() {
            let err = result.unwrap_err();
            assert!(
                err.contains("layout 'persistent'") && err.contains("persistent threads") && err.contains("65535"),
                "{err}"
            );
        } else {
            assert_eq!(result, Ok(256));
        }
    }
}
