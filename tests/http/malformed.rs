//! Malformed traffic gets its error, and the server keeps serving after it.

use serde_json::Value;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;

use super::{TestServer, expect_problem, one_vertex};
use crate::support::client;

async fn post_raw(server: &TestServer, body: impl Into<reqwest::Body>) -> reqwest::Response {
    client()
        .post(server.url("/v1/shade"))
        .header("content-type", "application/json")
        .body(body)
        .send()
        .await
        .unwrap()
}

async fn still_serves(server: &TestServer) {
    let response = server.post_json("/v1/shade", &one_vertex()).await;
    assert_eq!(response.status(), 200, "a normal request right after");
}

#[tokio::test]
async fn each_malformed_body_gets_its_error() {
    let server = TestServer::start().await;
    let deep = format!("{}{}", "[".repeat(100_000), "]".repeat(100_000));
    let cases: Vec<(String, u16, &str)> = vec![
        ("{\"vertices\": {\"positions\": [[0,0".into(), 400, ""),
        ("".into(), 400, ""),
        ("null".into(), 400, ""),
        ("[]".into(), 400, ""),
        ("{\"vertices\": 3}".into(), 400, "/vertices"),
        ("{\"vertices\": {\"positions\": [[1e400, 0, 0]], \"normals\": [[0,0,1]]}}".into(), 400, "/vertices/positions/0/0"),
        ("{\"vertices\": {\"positions\": [], \"normals\": []}} trailing".into(), 400, ""),
        ("{\"lights\": [{\"position\": [0, 0, 1, 0, 5]}], \"vertices\": {\"positions\": [], \"normals\": []}}".into(), 400, "/lights/0/position"),
        ("{\"precision\": \"exact\", \"vertices\": {\"positions\": [], \"normals\": []}}".into(), 400, "/precision"),
        (format!("{{\"material\": {deep}, \"vertices\": {{\"positions\": [], \"normals\": []}}}}"), 400, "/material"),
        ("\u{feff}{}".into(), 400, ""),
        // Regression: serde's structs also take an array of their fields,
        // whose errors then named fields the document does not have.
        ("{\"vertices\": [[], []]}".into(), 400, "/vertices"),
        ("{\"lights\": [[[0, 0, 1, 0]]], \"vertices\": {\"positions\": [], \"normals\": []}}".into(), 400, "/lights/0"),
        ("[{\"lights\": []}, {\"positions\": [], \"normals\": []}]".into(), 400, ""),
    ];
    for (body, status, pointer) in cases {
        let response = post_raw(&server, body.clone()).await;
        let problem = expect_problem(response, status, "malformed", None).await;
        let shown = &body[..body.len().min(80)];
        assert!(
            problem["pointer"]
                .as_str()
                .unwrap_or("")
                .starts_with(pointer),
            "{shown}: {problem}"
        );
    }
    still_serves(&server).await;
}

#[tokio::test]
async fn a_deeply_nested_body_is_refused_without_a_stack_overflow() {
    let server = TestServer::start().await;
    let deep = "[".repeat(1_000_000);
    let response = post_raw(&server, deep).await;
    expect_problem(response, 400, "malformed", None).await;
    still_serves(&server).await;
}

/// Sends the head of a request and reads what comes back before the body.
async fn raw_exchange(server: &TestServer, head: &str, body_chunk: &[u8], chunks: usize) -> String {
    let mut stream = TcpStream::connect(server.addr).await.unwrap();
    stream.write_all(head.as_bytes()).await.unwrap();
    for _ in 0..chunks {
        if stream.write_all(body_chunk).await.is_err() {
            break; // the server answered and closed: what we wanted
        }
    }
    let mut answer = Vec::new();
    let _ = stream.read_to_end(&mut answer).await;
    String::from_utf8_lossy(&answer).into_owned()
}

#[tokio::test]
async fn a_100_mb_body_is_refused_while_the_server_keeps_serving() {
    let server = TestServer::with(|c| c.max_body_bytes = 16 * 1024 * 1024).await;

    // Declared up front: refused on the length alone.
    let head = "POST /v1/shade HTTP/1.1\r\nhost: x\r\ncontent-type: application/json\r\n\
                content-length: 104857600\r\nconnection: close\r\n\r\n";
    let answer = raw_exchange(&server, head, b"", 0).await;
    assert!(answer.starts_with("HTTP/1.1 413"), "{answer}");
    assert!(answer.contains("application/problem+json"), "{answer}");

    // Streamed without a length: cut off at the limit.
    let head = "POST /v1/shade HTTP/1.1\r\nhost: x\r\ncontent-type: application/json\r\n\
                transfer-encoding: chunked\r\nconnection: close\r\n\r\n";
    let chunk = format!("100000\r\n{}\r\n", " ".repeat(0x100000));
    let answer = raw_exchange(&server, head, chunk.as_bytes(), 100).await;
    assert!(
        answer.starts_with("HTTP/1.1 413"),
        "{}",
        &answer[..answer.len().min(300)]
    );

    still_serves(&server).await;
}

#[tokio::test]
async fn a_body_shorter_than_its_length_times_out_with_408() {
    let server = TestServer::with(|c| c.body_timeout_ms = 300).await;
    let head = "POST /v1/shade HTTP/1.1\r\nhost: x\r\ncontent-type: application/json\r\n\
                content-length: 1000\r\nconnection: close\r\n\r\n{\"vertices\":";
    let mut stream = TcpStream::connect(server.addr).await.unwrap();
    stream.write_all(head.as_bytes()).await.unwrap();
    let mut answer = Vec::new();
    stream.read_to_end(&mut answer).await.unwrap();
    let answer = String::from_utf8_lossy(&answer);
    assert!(answer.starts_with("HTTP/1.1 408"), "{answer}");
    still_serves(&server).await;
}

#[tokio::test]
async fn wrong_types_everywhere_are_400s() {
    let server = TestServer::start().await;
    for (field, value) in [
        ("light_model", "[]"),
        ("material", "1"),
        ("lights", "{}"),
        ("view", "\"front\""),
        ("terms", "true"),
    ] {
        let body = format!(
            "{{\"{field}\": {value}, \"vertices\": {{\"positions\": [], \"normals\": []}}}}"
        );
        let response = post_raw(&server, body).await;
        let problem: Value = expect_problem(response, 400, "malformed", None).await;
        assert_eq!(problem["pointer"], format!("/{field}"), "{problem}");
    }
}

/// Asserts that the server closes `stream` (well within the 10 s this
/// waits, for a header timeout of a fraction of a second) and sends
/// nothing more before it does.
async fn closed_with_nothing_more(stream: &mut TcpStream) {
    let mut rest = Vec::new();
    let closed = tokio::time::timeout(
        std::time::Duration::from_secs(10),
        stream.read_to_end(&mut rest),
    )
    .await;
    assert!(closed.is_ok(), "the server closes the connection");
    assert!(rest.is_empty(), "{:?}", String::from_utf8_lossy(&rest));
}

#[tokio::test]
async fn a_client_that_connects_and_sends_nothing_is_cut_off() {
    let server = TestServer::with(|c| c.header_timeout_ms = 300).await;
    let mut stream = TcpStream::connect(server.addr).await.unwrap();
    closed_with_nothing_more(&mut stream).await;
    still_serves(&server).await;
}

#[tokio::test]
async fn a_client_trickling_its_headers_is_cut_off() {
    let server = TestServer::with(|c| c.header_timeout_ms = 300).await;
    let mut stream = TcpStream::connect(server.addr).await.unwrap();
    stream
        .write_all(b"POST /v1/shade HTTP/1.1\r\nhost: x\r\n")
        .await
        .unwrap();
    closed_with_nothing_more(&mut stream).await;
    still_serves(&server).await;
}

/// The head of `body` as a keep-alive POST to `/v1/shade`.
fn head_of(body: &str) -> String {
    format!(
        "POST /v1/shade HTTP/1.1\r\nhost: x\r\ncontent-type: application/json\r\n\
         content-length: {}\r\n\r\n",
        body.len()
    )
}

/// Reads one whole response (head and a `content-length` body) from `stream`.
async fn read_response(stream: &mut TcpStream) -> (u16, Vec<u8>) {
    let mut bytes = Vec::new();
    let mut chunk = [0u8; 4096];
    loop {
        if let Some(end) = bytes.windows(4).position(|w| w == b"\r\n\r\n") {
            let head = String::from_utf8_lossy(&bytes[..end]).to_ascii_lowercase();
            let length: usize = head
                .lines()
                .find_map(|l| l.strip_prefix("content-length:"))
                .map(|v| v.trim().parse().unwrap())
                .expect("a content-length");
            if bytes.len() >= end + 4 + length {
                let status = head[9..12].parse().unwrap();
                return (status, bytes[end + 4..end + 4 + length].to_vec());
            }
        }
        let n = stream.read(&mut chunk).await.unwrap();
        assert!(n > 0, "the connection closed mid-response");
        bytes.extend_from_slice(&chunk[..n]);
    }
}

#[tokio::test]
async fn an_idle_keep_alive_connection_is_closed_after_the_header_timeout() {
    let server = TestServer::with(|c| c.header_timeout_ms = 300).await;
    let body = one_vertex().to_string();
    let mut stream = TcpStream::connect(server.addr).await.unwrap();
    stream
        .write_all(format!("{}{body}", head_of(&body)).as_bytes())
        .await
        .unwrap();
    let (status, _) = read_response(&mut stream).await;
    assert_eq!(status, 200);
    // No second head: the server closes the connection, and nothing more
    // comes before it does.
    closed_with_nothing_more(&mut stream).await;
    still_serves(&server).await;
}

#[tokio::test]
async fn a_request_slower_than_the_header_timeout_is_still_answered() {
    // The head timeout bounds the wait for a head, not a request: a body
    // that takes longer than it (within the body timeout) is read and
    // answered, and the connection then serves a further request.
    let server = TestServer::with(|c| {
        c.header_timeout_ms = 200;
        c.body_timeout_ms = 10_000;
    })
    .await;
    let body = one_vertex().to_string();
    let (first, second) = body.split_at(body.len() / 2);
    let mut stream = TcpStream::connect(server.addr).await.unwrap();
    stream
        .write_all(format!("{}{first}", head_of(&body)).as_bytes())
        .await
        .unwrap();
    // The client's own pace, not a wait for the server: three header
    // timeouts pass between the halves of the body.
    tokio::time::sleep(std::time::Duration::from_millis(600)).await;
    stream.write_all(second.as_bytes()).await.unwrap();
    let (status, answer) = read_response(&mut stream).await;
    assert_eq!(status, 200, "{}", String::from_utf8_lossy(&answer));
    stream
        .write_all(format!("{}{body}", head_of(&body)).as_bytes())
        .await
        .unwrap();
    let (status, _) = read_response(&mut stream).await;
    assert_eq!(status, 200, "the connection still serves");
}
