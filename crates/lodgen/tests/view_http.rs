//! `lodgen view`'s server over real sockets: the page and script are served,
//! `/stream.bin` answers Range requests so that the chunks concatenate to the
//! stream, bad ranges get 416, and the level summary the browser test relies
//! on matches the progressive mesh. Also: a GLB carrying `LODGEN_progressive`
//! (built with `progressive::attach`) loads with the same stream and levels.

use lodgen::progressive::{attach, Placement};
use lodgen::view::{index_hash, ViewData, ViewServer};
use lodgen_pm::shapes::icosphere;
use lodgen_pm::stream::decode;
use serde_json::{json, Value};
use std::io::{Read, Write};
use std::net::TcpStream;

fn sphere_data() -> ViewData {
    let m = icosphere(3);
    ViewData::from_mesh("sphere".into(), &m.positions, &m.indices()).unwrap()
}

/// One HTTP/1.0-style request; returns (status, headers, body).
fn get(port: u16, path: &str, range: Option<&str>) -> (u16, String, Vec<u8>) {
    let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
    let range = range.map_or(String::new(), |r| format!("Range: {r}\r\n"));
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: 127.0.0.1\r\n{range}Connection: close\r\n\r\n"
    )
    .unwrap();
    let mut raw = Vec::new();
    s.read_to_end(&mut raw).unwrap();
    let split = raw.windows(4).position(|w| w == b"\r\n\r\n").unwrap();
    let head = String::from_utf8_lossy(&raw[..split]).into_owned();
    let status = head.split_whitespace().nth(1).unwrap().parse().unwrap();
    (status, head, raw[split + 4..].to_vec())
}

fn with_server(data: ViewData, f: impl FnOnce(u16)) {
    let server = ViewServer::bind(data, 0).unwrap();
    let port = server.port();
    let stop = server.stopper();
    let t = std::thread::spawn(move || server.run());
    f(port);
    stop.stop();
    t.join().unwrap();
}

#[test]
fn serves_page_info_and_stream_in_ranges() {
    let data = sphere_data();
    let stream = data.stream.clone();
    let levels = data.levels.clone();
    with_server(data, |port| {
        let (status, head, body) = get(port, "/", None);
        assert_eq!(status, 200);
        assert!(head.to_ascii_lowercase().contains("text/html"));
        assert!(String::from_utf8_lossy(&body).contains("viewer.js"));
        let (status, _, body) = get(port, "/viewer.js", None);
        assert_eq!(status, 200);
        assert!(String::from_utf8_lossy(&body).contains("window.lodgen"));

        let (status, _, body) = get(port, "/info.json", None);
        assert_eq!(status, 200);
        let info: Value = serde_json::from_slice(&body).unwrap();
        assert_eq!(info["streamBytes"], stream.len());
        assert_eq!(info["levels"], json!(levels));
        assert_eq!(info["source"], "pipeline");
        let cov: Vec<f64> = serde_json::from_value(info["screenCoverage"].clone()).unwrap();
        assert_eq!(cov.len(), levels.len());
        assert!(cov.windows(2).all(|w| w[0] >= w[1]), "{cov:?}");

        // chunks of 1000 bytes concatenate to the stream
        let mut got = Vec::new();
        let mut start = 0;
        while start < stream.len() {
            let end = (start + 1000).min(stream.len()) - 1;
            let (status, head, body) =
                get(port, "/stream.bin", Some(&format!("bytes={start}-{end}")));
            assert_eq!(status, 206);
            assert!(
                head.contains(&format!("bytes {start}-{end}/{}", stream.len())),
                "{head}"
            );
            got.extend_from_slice(&body);
            start = end + 1;
        }
        assert_eq!(got, stream);
        let (status, _, body) = get(port, "/stream.bin", None);
        assert_eq!((status, body), (200, stream.clone()));
        let (status, head, _) = get(
            port,
            "/stream.bin",
            Some(&format!("bytes={}-", stream.len())),
        );
        assert_eq!(status, 416);
        assert!(head.contains(&format!("bytes */{}", stream.len())));
        assert_eq!(get(port, "/nope", None).0, 404);
    });
}

#[test]
fn level_summary_matches_the_progressive_mesh() {
    let data = sphere_data();
    let (pm, levels) = decode(&data.stream).unwrap();
    assert_eq!(levels, data.levels);
    // finest first, the finest being the whole log
    assert_eq!(levels[0], pm.len());
    assert_eq!(*levels.last().unwrap(), 0);
    let s = data.level_summary().unwrap();
    for (i, &k) in levels.iter().enumerate() {
        let m = pm.mesh_at_splits(k);
        assert_eq!(s["levels"][i]["records"], k);
        assert_eq!(s["levels"][i]["triangles"], m.triangles.len());
        assert_eq!(s["levels"][i]["indexHash"], index_hash(&m.triangles));
    }
    assert_eq!(s["levels"][0]["triangles"], icosphere(3).triangles.len());
}

fn glb(root: &Value, bin: &[u8]) -> Vec<u8> {
    let mut json = serde_json::to_vec(root).unwrap();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let mut out = b"glTF".to_vec();
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&((12 + 8 + json.len() + 8 + bin.len()) as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(bin);
    out
}

#[test]
fn glb_and_gltf_with_the_extension_load_the_same_stream() {
    let data = sphere_data();
    let dir = std::env::temp_dir().join(format!("lodgen-view-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let doc = json!({
        "asset": {"version": "2.0"},
        "meshes": [{"primitives": [{"attributes": {}}]}, {"primitives": [{"attributes": {}}]}],
        "nodes": [{"mesh": 0, "extensions": {"MSFT_lod": {"ids": [1]}},
                   "extras": {"MSFT_screencoverage": [0.4, 0.001]}}, {"mesh": 1}],
        "extensionsUsed": ["MSFT_lod"],
    });

    let mut root = doc.clone();
    let mut bin = vec![7u8; 10];
    attach(
        &mut root,
        1,
        0,
        &data.stream,
        &data.levels,
        Placement::Glb { bin: &mut bin },
    )
    .unwrap();
    let path = dir.join("s.glb");
    std::fs::write(&path, glb(&root, &bin)).unwrap();
    let loaded = ViewData::load(&path).unwrap();
    assert_eq!(loaded.stream, data.stream);
    assert_eq!(loaded.levels, data.levels);
    assert_eq!(loaded.screen_coverage, vec![0.4, 0.001]);
    assert_eq!(loaded.source, "gltf");

    let mut root = doc.clone();
    attach(
        &mut root,
        1,
        0,
        &data.stream,
        &data.levels,
        Placement::External {
            uri: "s%20stream.bin".into(),
        },
    )
    .unwrap();
    std::fs::write(dir.join("s stream.bin"), &data.stream).unwrap();
    let path = dir.join("s.gltf");
    std::fs::write(&path, serde_json::to_vec(&root).unwrap()).unwrap();
    let loaded = ViewData::load(&path).unwrap();
    assert_eq!(loaded.stream, data.stream);

    // a GLB without the extension and without geometry, and a corrupt
    // stream, are errors
    let path = dir.join("plain.glb");
    std::fs::write(&path, glb(&doc, &[])).unwrap();
    assert!(ViewData::load(&path).is_err());
    let mut root = doc.clone();
    let mut bin = Vec::new();
    attach(
        &mut root,
        1,
        0,
        &data.stream[..data.stream.len() / 2],
        &data.levels,
        Placement::Glb { bin: &mut bin },
    )
    .unwrap();
    let path = dir.join("cut.glb");
    std::fs::write(&path, glb(&root, &bin)).unwrap();
    assert!(ViewData::load(&path).is_err());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn obj_input_goes_through_the_pipeline_and_bad_obj_is_an_error() {
    let dir = std::env::temp_dir().join(format!("lodgen-view-obj-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let m = icosphere(2);
    let mut text = String::new();
    for p in &m.positions {
        text += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    for t in &m.triangles {
        text += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    let path = dir.join("ico.obj");
    std::fs::write(&path, &text).unwrap();
    let d = ViewData::load(&path).unwrap();
    let s = d.level_summary().unwrap();
    assert_eq!(s["levels"][0]["triangles"], m.triangles.len());
    std::fs::write(&path, "v 0 0 0\nf 0 1 2\n").unwrap();
    let err = format!("{:#}", ViewData::load(&path).unwrap_err());
    assert!(
        err.contains("ico.obj:2") && err.contains("vertex 0"),
        "{err}"
    );
    assert!(ViewData::load(&dir.join("x.ply")).is_err());
    std::fs::remove_dir_all(&dir).unwrap();
}
