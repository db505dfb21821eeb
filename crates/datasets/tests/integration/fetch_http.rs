//! `fetch` against a tiny HTTP/1.1 server on 127.0.0.1 started by each test (std TcpListener in
//! a thread, bounded in requests and time). It serves archives the tests build from small
//! sequences: a `.tgz` of a synthetic TUM sequence from `synth` and a `.zip` of an EuRoC `mav0/`, and can break the first
//! transfer half-way (the client must resume with `Range`) or ignore ranges (it must restart).

use crate::common;

use datasets::fetch::{fetch, FetchEvent, FetchOptions};
use datasets::{load_euroc, load_tum, CameraId, DatasetError, Entry, EntryFormat};
use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::Path;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

#[derive(Clone, Default)]
struct ServerOptions {
    /// First data request: send only this many body bytes, then close.
    break_first_after: Option<usize>,
    /// Answer every request with the whole file (200), ignoring `Range`.
    ignore_range: bool,
}

struct Server {
    port: u16,
    /// Request heads received, in order.
    log: Arc<Mutex<Vec<String>>>,
}

fn read_head(s: &mut TcpStream) -> Option<String> {
    let mut buf = Vec::new();
    let mut b = [0u8; 1];
    while !buf.ends_with(b"\r\n\r\n") {
        if s.read(&mut b).ok()? == 0 || buf.len() > 16 * 1024 {
            return None;
        }
        buf.push(b[0]);
    }
    String::from_utf8(buf).ok()
}

/// Serves `body` at `/name` for at most 10 requests or 30 s, whichever comes first.
fn serve(name: &str, body: Vec<u8>, opts: ServerOptions) -> Server {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    listener.set_nonblocking(true).unwrap();
    let port = listener.local_addr().unwrap().port();
    let log = Arc::new(Mutex::new(Vec::new()));
    let log2 = log.clone();
    let path = format!("/{name}");
    std::thread::spawn(move || {
        let deadline = Instant::now() + Duration::from_secs(30);
        let mut served = 0;
        while served < 10 && Instant::now() < deadline {
            let mut s = match listener.accept() {
                Ok((s, _)) => s,
                Err(_) => {
                    std::thread::sleep(Duration::from_millis(5));
                    continue;
                }
            };
            served += 1;
            s.set_nonblocking(false).unwrap();
            s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
            let Some(head) = read_head(&mut s) else {
                continue;
            };
            log2.lock().unwrap().push(head.clone());
            let first_line = head.lines().next().unwrap_or("").to_string();
            if !first_line.starts_with(&format!("GET {path} ")) {
                let _ = s.write_all(
                    b"HTTP/1.1 404 Not Found\r\nContent-Length: 0\r\nConnection: close\r\n\r\n",
                );
                continue;
            }
            let range_start = head
                .lines()
                .find_map(|l| {
                    let (k, v) = l.split_once(':')?;
                    (k.trim().eq_ignore_ascii_case("range")).then(|| v.trim().to_string())
                })
                .and_then(|v| {
                    v.strip_prefix("bytes=")?
                        .strip_suffix('-')?
                        .parse::<usize>()
                        .ok()
                });
            let len = body.len();
            let (status, start) = match range_start {
                Some(n) if !opts.ignore_range && n >= len => {
                    let _ = s.write_all(
                        format!("HTTP/1.1 416 Range Not Satisfiable\r\nContent-Range: bytes */{len}\r\nContent-Length: 0\r\nConnection: close\r\n\r\n").as_bytes(),
                    );
                    continue;
                }
                Some(n) if !opts.ignore_range => (206, n),
                _ => (200, 0),
            };
            let mut resp = if status == 206 {
                format!(
                    "HTTP/1.1 206 Partial Content\r\nContent-Range: bytes {start}-{}/{len}\r\n",
                    len - 1
                )
            } else {
                "HTTP/1.1 200 OK\r\n".to_string()
            };
            resp += &format!(
                "Content-Type: application/octet-stream\r\nContent-Length: {}\r\nConnection: close\r\n\r\n",
                len - start
            );
            let _ = s.write_all(resp.as_bytes());
            let mut end = len;
            if served == 1 {
                if let Some(k) = opts.break_first_after {
                    end = k.min(len);
                }
            }
            let _ = s.write_all(&body[start..end.max(start)]);
            let _ = s.flush();
            let _ = s.shutdown(std::net::Shutdown::Both);
        }
    });
    Server { port, log }
}

fn tgz_of(dir: &Path, name_in_archive: &str) -> Vec<u8> {
    let enc = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    let mut tar = tar::Builder::new(enc);
    tar.append_dir_all(name_in_archive, dir).unwrap();
    tar.into_inner().unwrap().finish().unwrap()
}

fn entry(name: &str, format: EntryFormat, url: String, folder: &str) -> Entry {
    Entry {
        name: name.into(),
        paper_name: None,
        full_name: folder.into(),
        format,
        url: Some(url),
        folder: Some(folder.into()),
        camera: if format == EntryFormat::Euroc {
            CameraId::Euroc
        } else {
            CameraId::Fr3
        },
        class: None,
        paper: None,
        preset: None,
        imitates: None,
        frames: None,
        note: None,
    }
}

fn quick() -> FetchOptions {
    FetchOptions {
        connect_timeout: Duration::from_secs(2),
        response_timeout: Duration::from_secs(5),
        ..FetchOptions::default()
    }
}

#[test]
fn downloads_resumes_unpacks_tgz_and_verifies() {
    // A synthetic sequence from the generator, written in the TUM layout and packed as .tgz.
    let gen = synth::Generator::new(synth::SynthConfig::preset("clean").unwrap(), 3);
    let src = tempfile::tempdir().unwrap();
    let seq_dir = src.path().join("seq");
    datasets::write::write_synthetic(&gen, 3, &seq_dir, |_| {}).unwrap();
    let folder = "rgbd_dataset_freiburg3_tiny";
    let archive = tgz_of(&seq_dir, folder);
    let name = format!("{folder}.tgz");
    let server = serve(
        &name,
        archive.clone(),
        ServerOptions {
            break_first_after: Some(archive.len() / 2),
            ..Default::default()
        },
    );
    let root = tempfile::tempdir().unwrap();
    let e = entry(
        "tiny",
        EntryFormat::Tum,
        format!("http://127.0.0.1:{}/{name}", server.port),
        folder,
    );
    let mut events = Vec::new();
    let dir = fetch(&e, root.path(), &quick(), &mut |ev| events.push(ev.clone())).unwrap();
    assert_eq!(dir, root.path().join(folder));
    // The second request resumed where the first broke.
    let log = server.log.lock().unwrap().clone();
    assert_eq!(log.len(), 2, "{log:?}");
    assert!(
        log[1]
            .to_ascii_lowercase()
            .contains(&format!("range: bytes={}-", archive.len() / 2)),
        "{}",
        log[1]
    );
    assert!(events.contains(&FetchEvent::Retrying(1)), "{events:?}");
    assert!(events.iter().any(
        |ev| matches!(ev, FetchEvent::Start { offset, .. } if *offset as usize == archive.len() / 2)
    ));
    assert!(matches!(events.last(), Some(FetchEvent::Done(_))));
    // The unpacked sequence reads back identically; no temp dirs, archive removed.
    let seq = load_tum(&dir, Some(gen.camera())).unwrap();
    assert_eq!(seq.len(), 3);
    assert_eq!(*seq.frames[2].image, gen.frame(2).gray);
    let leftovers: Vec<_> = std::fs::read_dir(root.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".unpack"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    assert!(!root.path().join(".downloads").join(&name).exists());
    // Fetching again finds it in place, without a request.
    let mut again = Vec::new();
    fetch(&e, root.path(), &quick(), &mut |ev| again.push(ev.clone())).unwrap();
    assert!(matches!(again[0], FetchEvent::AlreadyPresent(_)));
    assert_eq!(server.log.lock().unwrap().len(), 2);
}

#[test]
fn server_ignoring_range_restarts_the_download() {
    let src = tempfile::tempdir().unwrap();
    common::write_tum(&src.path().join("s"), 2, 16, 12);
    let folder = "rgbd_dataset_freiburg3_norange";
    let archive = tgz_of(&src.path().join("s"), folder);
    let name = format!("{folder}.tgz");
    let server = serve(
        &name,
        archive.clone(),
        ServerOptions {
            break_first_after: Some(archive.len() / 3),
            ignore_range: true,
        },
    );
    let root = tempfile::tempdir().unwrap();
    let e = entry(
        "nr",
        EntryFormat::Tum,
        format!("http://127.0.0.1:{}/{name}", server.port),
        folder,
    );
    let mut events = Vec::new();
    let opts = FetchOptions {
        keep_archive: true,
        ..quick()
    };
    fetch(&e, root.path(), &opts, &mut |ev| events.push(ev.clone())).unwrap();
    assert!(events.contains(&FetchEvent::Restarted), "{events:?}");
    let kept = std::fs::read(root.path().join(".downloads").join(&name)).unwrap();
    assert_eq!(kept, archive);
}

#[test]
fn unpacks_euroc_zip_holding_mav0() {
    let src = tempfile::tempdir().unwrap();
    let mut zipw = zip::ZipWriter::new(std::io::Cursor::new(Vec::new()));
    let opts = zip::write::SimpleFileOptions::default();
    let yaml = |x: f64| {
        format!(
            "%YAML:1.0\nsensor_type: camera\nT_BS:\n  cols: 4\n  rows: 4\n  data: [1.0, 0.0, 0.0, {x},\n         0.0, 1.0, 0.0, 0.0,\n         0.0, 0.0, 1.0, 0.0,\n         0.0, 0.0, 0.0, 1.0]\nrate_hz: 20\nresolution: [32, 24]\ncamera_model: pinhole\nintrinsics: [30.0, 30.0, 16.0, 12.0] #fu, fv, cu, cv\ndistortion_model: radial-tangential\ndistortion_coefficients: [0.0, 0.0, 0.0, 0.0]\n"
        )
    };
    for (cam, x) in [("cam0", 0.0), ("cam1", 0.1)] {
        zipw.start_file(format!("mav0/{cam}/sensor.yaml"), opts)
            .unwrap();
        zipw.write_all(yaml(x).as_bytes()).unwrap();
        zipw.start_file(format!("mav0/{cam}/data.csv"), opts)
            .unwrap();
        zipw.write_all(
            b"#timestamp [ns],filename\n1000000000,1000000000.png\n1050000000,1050000000.png\n",
        )
        .unwrap();
        for ts in ["1000000000", "1050000000"] {
            let p = src.path().join(format!("{cam}{ts}.png"));
            image::GrayImage::from_fn(32, 24, |x, y| image::Luma([(x * 7 + y * 3) as u8]))
                .save(&p)
                .unwrap();
            zipw.start_file(format!("mav0/{cam}/data/{ts}.png"), opts)
                .unwrap();
            zipw.write_all(&std::fs::read(&p).unwrap()).unwrap();
        }
    }
    let archive = zipw.finish().unwrap().into_inner();
    let server = serve("V9_01_tiny.zip", archive, ServerOptions::default());
    let root = tempfile::tempdir().unwrap();
    let e = entry(
        "v901",
        EntryFormat::Euroc,
        format!("http://127.0.0.1:{}/V9_01_tiny.zip", server.port),
        "V9_01_tiny",
    );
    let dir = fetch(&e, root.path(), &quick(), &mut |_| {}).unwrap();
    assert!(dir.join("mav0/cam0/data.csv").is_file());
    let seq = load_euroc(&dir).unwrap();
    assert_eq!(seq.len(), 2);
    assert!((seq.camera.baseline() - 0.1).abs() < 1e-9);
    // Identity rig without distortion: rectification leaves the images as they were.
    assert_eq!(seq.frames[1].image.get(5, 7), 5 * 7 + 7 * 3);
}

#[test]
fn no_network_fails_fast_with_manual_instructions() {
    // A port with nobody listening: connection refused, like a machine without network.
    let port = {
        let l = TcpListener::bind("127.0.0.1:0").unwrap();
        l.local_addr().unwrap().port()
    };
    let root = tempfile::tempdir().unwrap();
    let url = format!("http://127.0.0.1:{port}/rgbd_dataset_freiburg1_xyz.tgz");
    let e = entry(
        "fr1_xyz",
        EntryFormat::Tum,
        url.clone(),
        "rgbd_dataset_freiburg1_xyz",
    );
    let t = Instant::now();
    let err = fetch(&e, root.path(), &quick(), &mut |_| {}).unwrap_err();
    assert!(
        t.elapsed() < Duration::from_secs(5),
        "took {:?}",
        t.elapsed()
    );
    assert!(matches!(err, DatasetError::Download { .. }), "{err}");
    let msg = err.to_string();
    assert!(msg.contains(&url), "{msg}");
    assert!(
        msg.contains(
            &root
                .path()
                .join("rgbd_dataset_freiburg1_xyz")
                .display()
                .to_string()
        ),
        "{msg}"
    );
    assert!(
        msg.contains("rgb.txt") && msg.contains(".downloads"),
        "{msg}"
    );
    // Nothing that looks like a sequence is left behind.
    assert!(!root.path().join("rgbd_dataset_freiburg1_xyz").exists());
}

#[test]
fn archive_placed_by_hand_is_used_without_network() {
    let src = tempfile::tempdir().unwrap();
    common::write_tum(&src.path().join("s"), 2, 16, 12);
    let folder = "rgbd_dataset_freiburg3_byhand";
    let root = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(root.path().join(".downloads")).unwrap();
    std::fs::write(
        root.path().join(".downloads").join(format!("{folder}.tgz")),
        tgz_of(&src.path().join("s"), folder),
    )
    .unwrap();
    let e = entry(
        "bh",
        EntryFormat::Tum,
        format!("http://127.0.0.1:9/{folder}.tgz"),
        folder,
    );
    let mut events = Vec::new();
    let dir = fetch(&e, root.path(), &quick(), &mut |ev| events.push(ev.clone())).unwrap();
    assert!(matches!(events[0], FetchEvent::UsingArchive(_)));
    assert!(dir.join("rgb.txt").is_file());
}

#[test]
fn corrupt_archive_is_an_error_and_leaves_nothing() {
    let root = tempfile::tempdir().unwrap();
    let folder = "rgbd_dataset_freiburg3_corrupt";
    std::fs::create_dir_all(root.path().join(".downloads")).unwrap();
    std::fs::write(
        root.path().join(".downloads").join(format!("{folder}.tgz")),
        b"not a gzip",
    )
    .unwrap();
    let e = entry(
        "c",
        EntryFormat::Tum,
        format!("http://127.0.0.1:9/{folder}.tgz"),
        folder,
    );
    let err = fetch(&e, root.path(), &quick(), &mut |_| {}).unwrap_err();
    assert!(matches!(err, DatasetError::Archive { .. }), "{err}");
    assert!(!root.path().join(folder).exists());
    let names: Vec<_> = std::fs::read_dir(root.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 1, "{names:?}"); // only .downloads
}
