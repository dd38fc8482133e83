//! Host jobs through the command mailbox in parameter words 32..49 (table 4.1 of the lift thesis;
//! src/mailbox.rs protocol).

use crate::common::*;
use asi_bus::Bus;
use asi_master::mailbox::{completed, post, Command, JobResult};
use asi_master::{EcFlags, Mode};
use asi_phy::SimDuration;

fn job(bus: &mut Bus, cmd: Command, args: &[u8]) -> (JobResult, [u8; 34]) {
    post(&mut bus.image_mut().output, cmd, args);
    let limit = bus.now() + SimDuration::from_millis(100);
    loop {
        let img = bus.image();
        if let Some((c, r, bytes)) = completed(&img.input, &img.output) {
            assert_eq!(c, cmd as u8);
            return (r, bytes);
        }
        let t = bus.poll_at();
        assert!(t < limit, "job {cmd:?} not done");
        bus.advance_to(t);
    }
}

#[test]
fn read_status_and_write_parameter() {
    let mut lab = running_lab(40);
    let (r, b) = job(lab.bus_mut(), Command::ReadStatus, &[5]);
    assert_eq!((r, b[0]), (JobResult::Ok, 0));
    let (r, b) = job(lab.bus_mut(), Command::WriteParameter, &[5, 0b0101]);
    assert_eq!((r, b[0]), (JobResult::Ok, 0b0101));
    assert_eq!(lab.bus().master().parameter_image(a(5)).get(), 0b0101);
    let id = lab.slave_id(5).expect("5");
    assert_eq!(
        lab.bus().slave(id).expect("slave").parameter().get(),
        0b0101
    );
    let (r, _) = job(lab.bus_mut(), Command::ReadStatus, &[9]);
    assert_eq!(r, JobResult::SlaveNotFound);
    let (r, _) = job(lab.bus_mut(), Command::WriteParameter, &[5, 16]);
    assert_eq!(r, JobResult::InvalidArgument);
}

#[test]
fn change_address_moves_a_slave() {
    let mut lab = running_lab(40);
    let (r, _) = job(lab.bus_mut(), Command::ChangeAddress, &[8, 9]);
    assert_eq!(r, JobResult::Ok);
    let id = lab.slave_id(8).expect("load sensor");
    let s = lab.bus().slave(id).expect("slave");
    assert_eq!((s.addr(), s.nv_address()), (a(9), addr(9)));
    let now = lab.bus().now();
    lab.bus_mut()
        .advance_to(now + SimDuration::from_millis(150));
    let m = lab.bus().master();
    assert!(m.lds().contains(a(9)) && !m.lds().contains(a(8)));
    assert!(
        !m.las().contains(a(9)),
        "9 is not projected: protected mode"
    );
    assert!(!m.flags().config_ok());
    let (r, _) = job(lab.bus_mut(), Command::ChangeAddress, &[9, 1]);
    assert_eq!(r, JobResult::AddressOccupied);
    let (r, _) = job(lab.bus_mut(), Command::ChangeAddress, &[20, 21]);
    assert_eq!(r, JobResult::SlaveNotFound);
}

#[test]
fn configuration_mode_and_store_actual_configuration() {
    let mut lab = running_lab(40);
    let (r, _) = job(
        lab.bus_mut(),
        Command::WriteProjected,
        &[9, 1, 0x70, 0xFF, 0xF],
    );
    assert_eq!(r, JobResult::NotAllowed, "protected mode");
    let (r, _) = job(lab.bus_mut(), Command::StoreActual, &[]);
    assert_eq!(r, JobResult::NotAllowed);
    let (r, _) = job(lab.bus_mut(), Command::ChangeAddress, &[8, 9]);
    assert_eq!(r, JobResult::Ok);
    let (r, _) = job(lab.bus_mut(), Command::SetMode, &[1]);
    assert_eq!(r, JobResult::Ok);
    assert_eq!(lab.bus().master().mode(), Mode::Configuration);
    let now = lab.bus().now();
    lab.bus_mut()
        .advance_to(now + SimDuration::from_millis(150));
    assert!(
        lab.bus().master().las().contains(a(9)),
        "configuration mode activates it"
    );
    assert_eq!(
        lab.bus().image().input.word(0) >> 15,
        0,
        "F3 = 0: configuration active"
    );
    let (r, _) = job(lab.bus_mut(), Command::StoreActual, &[]);
    assert_eq!(r, JobResult::Ok);
    let m = lab.bus().master();
    assert_eq!(m.lps(), m.lds());
    assert!(m.flags().config_ok());
    let (r, b) = job(lab.bus_mut(), Command::ReadProjected, &[9]);
    assert_eq!((r, &b[..4]), (JobResult::Ok, &[1, 0x11, 0xFF, 0xF][..]));
    let (r, _) = job(lab.bus_mut(), Command::SetMode, &[0]);
    assert_eq!(r, JobResult::Ok);
    assert_eq!(lab.bus().image().input.word(0) >> 15, 1);
}

#[test]
fn lists_flags_and_bad_commands() {
    let mut lab = running_lab(40);
    let (r, b) = job(lab.bus_mut(), Command::ReadList, &[1]);
    assert_eq!(r, JobResult::Ok);
    assert_eq!(&b[..8], &lab.bus().master().las().to_bytes());
    assert_eq!(b[0], 0b1111_1110, "slaves 1..7");
    assert_eq!(b[1], 0b0001_1101, "slaves 8, 10, 11, 12");
    let (r, b) = job(lab.bus_mut(), Command::ReadFlags, &[]);
    assert_eq!(r, JobResult::Ok);
    let f = EcFlags::from_bits(u16::from_be_bytes([b[0], b[1]]));
    assert!(f.config_ok() && f.normal_operation_active() && f.periphery_ok());
    let (r, b) = job(lab.bus_mut(), Command::ReadActual, &[10]);
    assert_eq!((r, &b[..3]), (JobResult::Ok, &[1, 0x73, 0xF5][..]));
    let (r, _) = job(lab.bus_mut(), Command::ReadList, &[7]);
    assert_eq!(r, JobResult::InvalidArgument);
    // An unknown command code.
    let w = lab.bus().image().output.word(32);
    lab.bus_mut()
        .image_mut()
        .output
        .set_word(32, (0x55 << 8) | ((w ^ 0x80) & 0x80));
    let now = lab.bus().now();
    lab.bus_mut().advance_to(now + us(400));
    let img = lab.bus().image();
    let (c, r, _) = completed(&img.input, &img.output).expect("done");
    assert_eq!((c, r), (0x55, JobResult::UnknownCommand));
}
