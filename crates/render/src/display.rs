//! Live view in [tev](https://github.com/Tom94/tev) over its TCP protocol (pbrt-v4's
//! `--display-server HOST:PORT`): the image is created once, then its changed tiles are sent
//! as the render converges.
//!
//! The render never waits for the viewer. [`Display::update`] only swaps the newest image into
//! a one-slot mailbox (an image not yet sent is replaced: stale updates are dropped); a
//! background thread connects, sends `CreateImage` (on every new connection, so a restarted
//! tev gets the image again), then `UpdateImage` packets of the 128 × 128 tiles whose pixels
//! changed since it last sent them, at most every [`Display::INTERVAL`]. When nothing listens
//! it says so once on stderr and tries again with later images; a failed send drops the
//! connection and the next image reconnects. [`Display::finish`] hands over the final image
//! and waits a bounded time ([`Display::final_wait`]) for it to go out.
//!
//! Packets (little-endian, as tev's `Ipc.cpp` reads them): a `u32` length of the whole
//! packet, a type byte (4 `CreateImage`, 6 `UpdateImage` version 3), `grabFocus` as a byte,
//! the image name as a NUL-terminated string; then `CreateImage`: width, height, channel count
//! (`i32`) and the channel names; `UpdateImage`: the channel count, names, x, y, width,
//! height (`i32`), per-channel offsets and strides (`i64`) into the interleaved `f32` data
//! that follows.

use std::io::Write;
use std::net::{SocketAddr, TcpStream, ToSocketAddrs};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// One image as tev receives it: interleaved `f32` channels, row-major, y down.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// Channel names (tev groups `R`, `G`, `B` into one layer; `albedo.R` … into another).
    pub channels: Vec<String>,
    /// `width × height × channels.len()` values.
    pub data: Vec<f32>,
}

impl Frame {
    /// An RGB frame of an image.
    pub fn rgb(image: &crate::film::Image) -> Frame {
        let mut data = Vec::with_capacity(image.pixels.len() * 3);
        for p in &image.pixels {
            data.extend_from_slice(&[p.x, p.y, p.z]);
        }
        Frame {
            width: image.width,
            height: image.height,
            channels: ["R", "G", "B"].map(String::from).to_vec(),
            data,
        }
    }

    /// Appends an image's RGB as three more channels `prefix.R`, `prefix.G`, `prefix.B`
    /// (same size).
    pub fn with_layer(mut self, prefix: &str, image: &crate::film::Image) -> Frame {
        assert_eq!((image.width, image.height), (self.width, self.height));
        let n = self.channels.len();
        let mut data = Vec::with_capacity(image.pixels.len() * (n + 3));
        for (i, p) in image.pixels.iter().enumerate() {
            data.extend_from_slice(&self.data[i * n..(i + 1) * n]);
            data.extend_from_slice(&[p.x, p.y, p.z]);
        }
        self.data = data;
        for c in ["R", "G", "B"] {
            self.channels.push(format!("{prefix}.{c}"));
        }
        self
    }
}

const CREATE_IMAGE: u8 = 4;
const UPDATE_IMAGE_V3: u8 = 6;
/// Tile side of the updates (tev's own Python client sends 128 × 128).
const TILE: u32 = 128;

/// A packet under construction; [`Packet::finish`] writes the length in front.
struct Packet(Vec<u8>);

impl Packet {
    fn new(kind: u8, grab_focus: bool, name: &str) -> Packet {
        let mut p = Packet(vec![0; 4]);
        p.0.push(kind);
        p.0.push(grab_focus as u8);
        p.string(name);
        p
    }
    fn string(&mut self, s: &str) {
        // tev reads up to the first NUL.
        self.0.extend(s.bytes().filter(|&b| b != 0));
        self.0.push(0);
    }
    fn i32(&mut self, v: i32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn i64(&mut self, v: i64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn finish(mut self) -> Vec<u8> {
        let n = self.0.len() as u32;
        self.0[..4].copy_from_slice(&n.to_le_bytes());
        self.0
    }
}

/// The `CreateImage` packet of a frame's size and channels.
pub fn create_image_packet(name: &str, frame: &Frame) -> Vec<u8> {
    let mut p = Packet::new(CREATE_IMAGE, true, name);
    p.i32(frame.width as i32);
    p.i32(frame.height as i32);
    p.i32(frame.channels.len() as i32);
    for c in &frame.channels {
        p.string(c);
    }
    p.finish()
}

/// The `UpdateImage` (version 3) packet of the tile at (x, y) of size w × h.
pub fn update_image_packet(
    name: &str,
    frame: &Frame,
    (x, y, w, h): (u32, u32, u32, u32),
) -> Vec<u8> {
    let n = frame.channels.len();
    let mut p = Packet::new(UPDATE_IMAGE_V3, false, name);
    p.i32(n as i32);
    for c in &frame.channels {
        p.string(c);
    }
    for v in [x, y, w, h] {
        p.i32(v as i32);
    }
    for c in 0..n {
        p.i64(c as i64);
    }
    for _ in 0..n {
        p.i64(n as i64);
    }
    p.0.reserve((w * h) as usize * n * 4);
    for row in y..y + h {
        let start = (row * frame.width + x) as usize * n;
        for v in &frame.data[start..start + (w as usize) * n] {
            p.0.extend_from_slice(&v.to_le_bytes());
        }
    }
    p.finish()
}

/// The tiles of a `width × height` image, row by row: (x, y, w, h).
fn tiles(width: u32, height: u32) -> impl Iterator<Item = (u32, u32, u32, u32)> {
    (0..height.div_ceil(TILE)).flat_map(move |ty| {
        (0..width.div_ceil(TILE)).map(move |tx| {
            let (x, y) = (tx * TILE, ty * TILE);
            (x, y, TILE.min(width - x), TILE.min(height - y))
        })
    })
}

/// Whether the tile's values differ between two frames of the same layout (bitwise, so a NaN
/// that stays NaN is unchanged).
fn tile_changed(a: &Frame, b: &Frame, (x, y, w, h): (u32, u32, u32, u32)) -> bool {
    let n = a.channels.len();
    (y..y + h).any(|row| {
        let s = (row * a.width + x) as usize * n;
        let e = s + w as usize * n;
        a.data[s..e]
            .iter()
            .zip(&b.data[s..e])
            .any(|(p, q)| p.to_bits() != q.to_bits())
    })
}

#[derive(Default)]
struct Mailbox {
    /// The newest frame not yet taken by the sender.
    pending: Option<Frame>,
    /// No more frames will come (the pending one, if any, is the last).
    closing: bool,
    /// The sender has finished with the last frame (sent, or given up).
    done: bool,
}

/// The live view's handle on the render side (see the module docs).
pub struct Display {
    shared: Arc<(Mutex<Mailbox>, Condvar)>,
    thread: Option<JoinHandle<()>>,
}

impl Display {
    /// Shortest time between two rounds of updates.
    pub const INTERVAL: Duration = Duration::from_millis(250);
    /// Connection and write time-outs (a viewer that stops reading loses its connection).
    const TIMEOUT: Duration = Duration::from_secs(2);

    /// Starts the sender for `server` (`HOST:PORT`), naming the image `name` in tev. Fails only
    /// on an address that cannot be parsed; a viewer that is not running is a warning later.
    pub fn start(server: &str, name: &str) -> Result<Display, String> {
        let addr = server
            .to_socket_addrs()
            .map_err(|e| format!("--display-server {server}: {e}"))?
            .next()
            .ok_or_else(|| format!("--display-server {server}: no address"))?;
        let shared = Arc::new((Mutex::new(Mailbox::default()), Condvar::new()));
        let worker = Sender {
            addr,
            server: server.to_string(),
            name: name.to_string(),
            shared: shared.clone(),
        };
        let thread = std::thread::Builder::new()
            .name("tev".into())
            .spawn(move || worker.run())
            .map_err(|e| format!("--display-server: {e}"))?;
        Ok(Display {
            shared,
            thread: Some(thread),
        })
    }

    /// Offers the newest image (replacing one not yet sent). Never blocks on the network.
    pub fn update(&self, frame: Frame) {
        let (lock, cvar) = &*self.shared;
        let mut m = lock.lock().unwrap_or_else(|e| e.into_inner());
        m.pending = Some(frame);
        cvar.notify_all();
    }

    /// The longest wait for the final image after a render that took `elapsed`: 2 % of it,
    /// at least half a second (a local tev takes a 4K image in well under that), so that a
    /// slow or stuck viewer costs the render at most that.
    pub fn final_wait(elapsed: Duration) -> Duration {
        (elapsed / 50).max(Duration::from_millis(500))
    }

    /// Hands over the final image and waits up to `wait` for the sender to deliver it;
    /// returns whether it did.
    pub fn finish(mut self, frame: Frame, wait: Duration) -> bool {
        let (lock, cvar) = &*self.shared;
        let deadline = Instant::now() + wait;
        let mut m = lock.lock().unwrap_or_else(|e| e.into_inner());
        m.pending = Some(frame);
        m.closing = true;
        cvar.notify_all();
        while !m.done {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                // The sender is stuck on a slow viewer: leave it (it ends with the process).
                self.thread.take();
                return false;
            }
            m = cvar
                .wait_timeout(m, left)
                .unwrap_or_else(|e| e.into_inner())
                .0;
        }
        drop(m);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        true
    }
}

impl Drop for Display {
    fn drop(&mut self) {
        // Dropped without `finish` (an error path): stop the sender without waiting.
        let (lock, cvar) = &*self.shared;
        let mut m = lock.lock().unwrap_or_else(|e| e.into_inner());
        m.closing = true;
        cvar.notify_all();
    }
}

struct Sender {
    addr: SocketAddr,
    server: String,
    name: String,
    shared: Arc<(Mutex<Mailbox>, Condvar)>,
}

impl Sender {
    fn run(self) {
        let mut conn: Option<TcpStream> = None;
        // What the viewer has: the last frame sent on this connection.
        let mut shown: Option<Frame> = None;
        let mut warned = false;
        let mut last_round: Option<Instant> = None;
        while let Some((mut frame, mut last)) = self.wait_frame() {
            if !last && let Some(t) = last_round {
                std::thread::sleep(Display::INTERVAL.saturating_sub(t.elapsed()));
                // A newer frame may have come meanwhile: send that one instead.
                if let Some(newer) = self.take_frame() {
                    (frame, last) = newer;
                }
            }
            self.round(&mut conn, &mut shown, &mut warned, frame, last);
            last_round = Some(Instant::now());
            if last {
                break;
            }
        }
        self.finish();
    }

    /// The next frame and whether it is the last; `None` when closing with nothing left.
    fn wait_frame(&self) -> Option<(Frame, bool)> {
        let (lock, cvar) = &*self.shared;
        let mut m = lock.lock().unwrap_or_else(|e| e.into_inner());
        while m.pending.is_none() && !m.closing {
            m = cvar.wait(m).unwrap_or_else(|e| e.into_inner());
        }
        m.pending.take().map(|f| (f, m.closing))
    }

    fn take_frame(&self) -> Option<(Frame, bool)> {
        let (lock, _) = &*self.shared;
        let mut m = lock.lock().unwrap_or_else(|e| e.into_inner());
        m.pending.take().map(|f| (f, m.closing))
    }

    fn finish(&self) {
        let (lock, cvar) = &*self.shared;
        let mut m = lock.lock().unwrap_or_else(|e| e.into_inner());
        m.done = true;
        cvar.notify_all();
    }

    /// Sends one frame: connects if needed (creating the image anew on a new connection), then
    /// the tiles that changed. A failure drops the connection (retried with the next frame).
    fn round(
        &self,
        conn: &mut Option<TcpStream>,
        shown: &mut Option<Frame>,
        warned: &mut bool,
        frame: Frame,
        last: bool,
    ) {
        if conn.is_none() {
            match TcpStream::connect_timeout(&self.addr, Display::TIMEOUT) {
                Ok(s) => {
                    let _ = s.set_write_timeout(Some(Display::TIMEOUT));
                    let _ = s.set_nodelay(true);
                    *conn = Some(s);
                    *shown = None;
                    if *warned {
                        eprintln!("live view: connected to tev at {}", self.server);
                        *warned = false;
                    }
                }
                Err(e) => {
                    if !*warned || last {
                        eprintln!(
                            "warning: live view: no tev at {} ({e}){}",
                            self.server,
                            if last {
                                "; the final image was not shown"
                            } else {
                                "; rendering on, will try again"
                            }
                        );
                        *warned = true;
                    }
                    return;
                }
            }
        }
        let stream = conn.as_mut().expect("connected above");
        let same_layout = shown.as_ref().is_some_and(|s| {
            (s.width, s.height, &s.channels) == (frame.width, frame.height, &frame.channels)
        });
        let result = (|| -> std::io::Result<()> {
            if !same_layout {
                stream.write_all(&create_image_packet(&self.name, &frame))?;
            }
            for t in tiles(frame.width, frame.height) {
                let changed = match shown {
                    Some(s) if same_layout => tile_changed(s, &frame, t),
                    _ => true,
                };
                if changed {
                    stream.write_all(&update_image_packet(&self.name, &frame, t))?;
                }
            }
            stream.flush()
        })();
        match result {
            Ok(()) => *shown = Some(frame),
            Err(e) => {
                let why = match e.kind() {
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut => {
                        "it stopped reading".to_string()
                    }
                    _ => e.to_string(),
                };
                eprintln!(
                    "warning: live view: lost tev at {} ({why}){}",
                    self.server,
                    if last {
                        "; the final image was not shown"
                    } else {
                        "; will reconnect"
                    }
                );
                *conn = None;
                *shown = None;
                *warned = true;
            }
        }
    }
}

/// A minimal tev for tests: accepts one connection on a listener and reassembles the image
/// from the packets it reads, checking each is well formed (it panics otherwise).
pub mod mock {
    use super::{CREATE_IMAGE, UPDATE_IMAGE_V3};
    use std::io::Read;
    use std::net::TcpListener;
    use std::thread::JoinHandle;

    /// What the mock viewer holds.
    #[derive(Default, Debug)]
    pub struct Viewer {
        /// `CreateImage` packets received.
        pub created: u32,
        /// `UpdateImage` packets received.
        pub updates: u32,
        pub size: (u32, u32),
        pub channels: Vec<String>,
        /// Interleaved channels, row-major (NaN where no update wrote).
        pub data: Vec<f32>,
        /// The image name of every packet.
        pub name: String,
    }

    fn cstr(b: &[u8], at: &mut usize) -> String {
        let end = b[*at..].iter().position(|&c| c == 0).expect("NUL") + *at;
        let s = String::from_utf8(b[*at..end].to_vec()).expect("UTF-8");
        *at = end + 1;
        s
    }
    fn i32_at(b: &[u8], at: &mut usize) -> i32 {
        let v = i32::from_le_bytes(b[*at..*at + 4].try_into().expect("4 bytes"));
        *at += 4;
        v
    }
    fn i64_at(b: &[u8], at: &mut usize) -> i64 {
        let v = i64::from_le_bytes(b[*at..*at + 8].try_into().expect("8 bytes"));
        *at += 8;
        v
    }

    impl Viewer {
        /// Applies one packet (without its length field).
        pub fn apply(&mut self, b: &[u8]) {
            let mut at = 0;
            let kind = b[at];
            at += 1;
            assert!(b[at] <= 1, "grabFocus is a bool");
            at += 1;
            let name = cstr(b, &mut at);
            if self.created > 0 {
                assert_eq!(name, self.name, "one image");
            }
            self.name = name;
            match kind {
                CREATE_IMAGE => {
                    let (w, h) = (i32_at(b, &mut at), i32_at(b, &mut at));
                    let n = i32_at(b, &mut at);
                    assert!(w > 0 && h > 0 && n > 0);
                    self.channels = (0..n).map(|_| cstr(b, &mut at)).collect();
                    assert_eq!(at, b.len(), "CreateImage size");
                    self.size = (w as u32, h as u32);
                    self.data = vec![f32::NAN; (w * h * n) as usize];
                    self.created += 1;
                }
                UPDATE_IMAGE_V3 => {
                    assert!(self.created > 0, "an update before CreateImage");
                    let n = i32_at(b, &mut at) as usize;
                    let names: Vec<String> = (0..n).map(|_| cstr(b, &mut at)).collect();
                    assert_eq!(names, self.channels);
                    let [x, y, w, h] = [0; 4].map(|_| i32_at(b, &mut at) as u32);
                    assert!(x + w <= self.size.0 && y + h <= self.size.1 && w > 0 && h > 0);
                    let offsets: Vec<i64> = (0..n).map(|_| i64_at(b, &mut at)).collect();
                    let strides: Vec<i64> = (0..n).map(|_| i64_at(b, &mut at)).collect();
                    let values: Vec<f32> = b[at..]
                        .chunks_exact(4)
                        .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")))
                        .collect();
                    assert_eq!(values.len() * 4, b.len() - at, "whole floats");
                    assert_eq!(values.len(), (w * h) as usize * n, "payload size");
                    for py in 0..h {
                        for px in 0..w {
                            let i = (py * w + px) as usize;
                            let dst = ((y + py) * self.size.0 + x + px) as usize * n;
                            for c in 0..n {
                                let src = offsets[c] as usize + i * strides[c] as usize;
                                self.data[dst + c] = values[src];
                            }
                        }
                    }
                    self.updates += 1;
                }
                k => panic!("unexpected packet type {k}"),
            }
        }

        /// Accepts one connection on `listener` and reads packets until the peer closes it
        /// (or, with `stop_after`, until that many packets, then drops the connection and the
        /// listener: a tev that quits).
        pub fn serve(listener: TcpListener, stop_after: Option<u32>) -> JoinHandle<Viewer> {
            std::thread::spawn(move || {
                let (mut s, _) = listener.accept().expect("a connection");
                let mut v = Viewer::default();
                let mut len = [0u8; 4];
                let mut packets = 0;
                while stop_after.is_none_or(|n| packets < n) && s.read_exact(&mut len).is_ok() {
                    let n = u32::from_le_bytes(len) as usize;
                    assert!(n > 4, "the length counts itself");
                    let mut b = vec![0u8; n - 4];
                    s.read_exact(&mut b).expect("a whole packet");
                    v.apply(&b);
                    packets += 1;
                }
                v
            })
        }

        /// Channel `c` of pixel (x, y).
        pub fn get(&self, x: u32, y: u32, c: usize) -> f32 {
            self.data[(y * self.size.0 + x) as usize * self.channels.len() + c]
        }
    }
}

#[cfg(test)]
mod tests {
    use super::mock::Viewer;
    use super::*;
    use crate::film::Image;
    use crate::math::Vec3;
    use std::net::TcpListener;

    fn image(w: u32, h: u32, k: f32) -> Image {
        let mut img = Image::new(w, h);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            *p = Vec3::new(i as f32 * k, -(i as f32), k);
        }
        img
    }

    #[test]
    fn viewer_reassembles_exactly_the_final_image() {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap().to_string();
        let viewer = Viewer::serve(listener, None);
        let d = Display::start(&addr, "out.exr").unwrap();
        // 300 × 200: tiles of 128 and ragged edges; several updates, most dropped as stale.
        for k in 0..5 {
            d.update(Frame::rgb(&image(300, 200, k as f32)));
        }
        let last = Frame::rgb(&image(300, 200, 7.5)).with_layer("albedo", &image(300, 200, 0.5));
        assert!(d.finish(last.clone(), Duration::from_secs(5)));
        let v = viewer.join().unwrap();
        assert_eq!(v.size, (300, 200));
        assert_eq!(v.channels, last.channels);
        assert_eq!(
            v.data.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            last.data.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        );
        assert!(v.created >= 1 && v.updates >= 6, "{} updates", v.updates);
        assert_eq!(v.name, "out.exr");
    }

    #[test]
    fn only_changed_tiles_are_sent_again() {
        let listener = TcpListener::bind("127.0.0.1:0").unwrap();
        let addr = listener.local_addr().unwrap().to_string();
        let viewer = Viewer::serve(listener, None);
        let d = Display::start(&addr, "x").unwrap();
        let a = Frame::rgb(&image(256, 256, 1.0));
        d.update(a.clone());
        std::thread::sleep(Duration::from_millis(100));
        let mut b = a.clone();
        b.data[0] = 42.0; // the first tile only
        assert!(d.finish(b.clone(), Duration::from_secs(5)));
        let v = viewer.join().unwrap();
        assert_eq!(v.data, b.data);
        // 4 tiles for the first image (or none if it was replaced first), 1 or 4 for the second.
        assert!(v.updates == 5 || v.updates == 4, "{} updates", v.updates);
        assert_eq!(v.created, 1);
    }

    #[test]
    fn no_viewer_is_a_warning_not_an_error() {
        // A port nothing listens on: bind, read the port, close.
        let port = TcpListener::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .port();
        let d = Display::start(&format!("127.0.0.1:{port}"), "x").unwrap();
        d.update(Frame::rgb(&image(8, 8, 1.0)));
        // The sender gives up on the final image quickly (connection refused) and says done.
        assert!(d.finish(Frame::rgb(&image(8, 8, 2.0)), Duration::from_secs(5)));
    }

    #[test]
    fn bad_addresses_are_refused() {
        assert!(Display::start("no port here", "x").is_err());
    }
}
