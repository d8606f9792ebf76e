//! ESI parsing per file of the real vendor corpus (`../shared/esi-corpus`, or
//! `ECDRIVE_ESI_CORPUS`): the bytes read, decoded and parsed into every device, throughput in
//! bytes per second (criterion prints MiB/s), and the consistency check of the whole file.
//! The largest file of the corpus (a modular I/O coupler) is 2.6 MB.
//!
//! Run with `cargo bench --bench esi_parse`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use ecdrive::esi::EsiFile;
use std::path::{Path, PathBuf};
use std::time::Duration;

fn corpus() -> Vec<PathBuf> {
    let dir = std::env::var_os("ECDRIVE_ESI_CORPUS")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/esi-corpus"));
    let Ok(manifest) = std::fs::read_to_string(dir.join("MANIFEST.tsv")) else {
        eprintln!("no ESI corpus at {}", dir.display());
        return Vec::new();
    };
    manifest
        .lines()
        .skip(1)
        .filter_map(|l| l.split('\t').next())
        .filter(|p| !p.is_empty())
        .map(|p| dir.join(p))
        .collect()
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("esi_parse");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(200))
        .measurement_time(Duration::from_secs(2));
    for path in corpus() {
        let bytes = std::fs::read(&path).expect("read");
        let name = path
            .file_name()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        g.throughput(Throughput::Bytes(bytes.len() as u64));
        g.bench_function(format!("parse/{name}"), |b| {
            b.iter(|| EsiFile::parse_bytes(&bytes).expect("parses"))
        });
        let f = EsiFile::parse_bytes(&bytes).expect("parses");
        g.bench_function(format!("check/{name}"), |b| b.iter(|| f.check()));
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
