//! A slave samples its inputs when it has received the request: the request's last pulse plus
//! the 9 µs pause that ends the telegram (84 + 9 = 93 µs after the request starts). Inputs set
//! before that instant are in the response, inputs set after it wait for the next cycle.

use crate::common::*;
use asi_phy::{Call, SimDuration};

fn first_ready_exchange(offset_us: u64) -> (SimDuration, u64) {
    let mut lab = running_lab(40);
    lab.bus_mut().advance_to(ms(45));
    let _ = lab.bus_mut().drain_trace();
    // Find the start of the next Data_Exchange with the converter (address 7).
    let cycle = us(13 * 154);
    let now = lab.bus().now();
    lab.bus_mut().advance_to(now + cycle);
    let last7 = lab
        .bus_mut()
        .drain_trace()
        .into_iter()
        .rfind(|r| matches!(r.request.call(), Call::DataExchange { address, .. } if address.get() == 7))
        .expect("an exchange with 7")
        .start;
    let next7 = last7 + cycle;
    lab.bus_mut().advance_to(next7 + us(offset_us));
    lab.converter_mut().expect("converter").set_ready(true);
    lab.bus_mut().advance_to(next7 + cycle + cycle);
    let first = lab
        .bus_mut()
        .drain_trace()
        .into_iter()
        .find(|r| {
            matches!(r.request.call(), Call::DataExchange { address, .. } if address.get() == 7)
                && r.response.is_some_and(|x| x.data().bit(0))
        })
        .expect("ready seen");
    (first.start - next7, offset_us)
}

#[test]
fn inputs_are_sampled_when_the_request_has_been_received() {
    // Set 92 µs after the request started: still in time for this exchange.
    assert_eq!(first_ready_exchange(92).0, SimDuration::ZERO);
    // Set 93 µs after: the slave sampled at 93 µs (events at that instant come first).
    assert_eq!(first_ready_exchange(93).0, us(13 * 154));
    assert_eq!(first_ready_exchange(100).0, us(13 * 154));
}
