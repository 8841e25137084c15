//! The byte stream to a plant: a child process's stdin/stdout or a TCP
//! connection, read line by line with a length limit and a timeout.
//!
//! # Theory of operation
//! A reader thread owns the plant's output: it reads one line at a time
//! (at most [`MAX_LINE`] bytes before the newline) and sends it over a
//! channel; the session waits on the channel with the plant's timeout, so
//! a plant that says nothing is a [`Fault::Timeout`], never a hang. The
//! thread stops at the end of the stream, at an over-long line or at a
//! read error, each sent as the stream's last item. Closing the
//! [`Link`] ends the child (after its `end`, a grace period, then kill)
//! or shuts the socket, which ends the thread.

use crate::error::Fault;
use crate::wire::MAX_LINE;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::{Shutdown, TcpStream, ToSocketAddrs};
use std::process::{Child, ChildStdin, Command, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::thread;
use std::time::{Duration, Instant};

/// Where a plant is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Endpoint {
    /// A program to start, as a shell command line (`sh -c 'exec …'`): it
    /// speaks on its standard input and output; its standard error is
    /// passed on.
    Command(String),
    /// `HOST:PORT` of a plant already listening.
    Tcp(String),
}

/// What the reader thread sends: a line without its newline, or how the
/// stream ended.
type Item = Result<Vec<u8>, Fault>;

/// How long a plant has to exit after its `end` before it is killed.
const EXIT_GRACE: Duration = Duration::from_secs(5);

/// The output side of the stream.
enum Sink {
    Child(Option<ChildStdin>, Child),
    Tcp(TcpStream),
}

/// An open stream to a plant.
pub struct Link {
    lines: Receiver<Item>,
    sink: Sink,
    timeout: Duration,
}

impl Link {
    /// Starts or connects to the plant at `endpoint`; `timeout` bounds the
    /// wait for each of its lines (and for a TCP connection).
    ///
    /// # Errors
    /// [`Fault::Unreachable`] when the program cannot be started or the
    /// address not reached.
    pub fn open(endpoint: &Endpoint, timeout: Duration) -> Result<Self, Fault> {
        match endpoint {
            Endpoint::Command(line) => {
                let mut child = Command::new("sh")
                    .arg("-c")
                    .arg(format!("exec {line}"))
                    .stdin(Stdio::piped())
                    .stdout(Stdio::piped())
                    .stderr(Stdio::inherit())
                    .spawn()
                    .map_err(|e| Fault::Unreachable(format!("{line}: {e}")))?;
                let stdin = child.stdin.take();
                let stdout = child
                    .stdout
                    .take()
                    .ok_or_else(|| Fault::Unreachable(format!("{line}: no standard output")))?;
                Ok(Self {
                    lines: spawn_reader(stdout),
                    sink: Sink::Child(stdin, child),
                    timeout,
                })
            }
            Endpoint::Tcp(address) => {
                let stream = connect(address, timeout)?;
                // Lines are small and the loop is lockstep: no batching.
                let _ = stream.set_nodelay(true);
                let reader = stream
                    .try_clone()
                    .map_err(|e| Fault::Unreachable(format!("{address}: {e}")))?;
                Ok(Self {
                    lines: spawn_reader(reader),
                    sink: Sink::Tcp(stream),
                    timeout,
                })
            }
        }
    }

    /// The plant's next line (newline removed).
    ///
    /// # Errors
    /// [`Fault::Timeout`], [`Fault::EndOfStream`], [`Fault::LineTooLong`]
    /// or [`Fault::Io`].
    pub fn read_line(&mut self) -> Result<Vec<u8>, Fault> {
        match self.lines.recv_timeout(self.timeout) {
            Ok(item) => item,
            Err(RecvTimeoutError::Timeout) => Err(Fault::Timeout(self.timeout.as_secs_f64())),
            Err(RecvTimeoutError::Disconnected) => Err(Fault::EndOfStream),
        }
    }

    /// Sends `line` (with its newline) to the plant.
    ///
    /// # Errors
    /// [`Fault::Io`] when the plant no longer reads.
    pub fn write_line(&mut self, line: &str) -> Result<(), Fault> {
        let result = match &mut self.sink {
            Sink::Child(Some(stdin), _) => stdin
                .write_all(line.as_bytes())
                .and_then(|()| stdin.flush()),
            Sink::Child(None, _) => return Err(Fault::Io("the plant's input is closed".into())),
            Sink::Tcp(stream) => stream.write_all(line.as_bytes()),
        };
        result.map_err(|e| Fault::Io(e.to_string()))
    }

    /// Ends the link: closes the plant's input, waits up to a grace period
    /// for a child to exit (then kills it) and returns its exit status in
    /// words when it failed. `kill` ends a child at once.
    pub fn close(self, kill: bool) -> Option<String> {
        match self.sink {
            Sink::Tcp(stream) => {
                let _ = stream.shutdown(Shutdown::Both);
                None
            }
            Sink::Child(stdin, mut child) => {
                drop(stdin);
                let deadline = Instant::now() + if kill { Duration::ZERO } else { EXIT_GRACE };
                loop {
                    match child.try_wait() {
                        Ok(Some(status)) if status.success() => return None,
                        Ok(Some(status)) => return Some(status.to_string()),
                        Ok(None) if Instant::now() < deadline => {
                            thread::sleep(Duration::from_millis(5));
                        }
                        Ok(None) => {
                            let _ = child.kill();
                            let _ = child.wait();
                            return (!kill).then(|| {
                                format!("no exit within {} s: killed", EXIT_GRACE.as_secs())
                            });
                        }
                        Err(e) => return Some(e.to_string()),
                    }
                }
            }
        }
    }
}

fn connect(address: &str, timeout: Duration) -> Result<TcpStream, Fault> {
    let unreachable = |e: &dyn std::fmt::Display| Fault::Unreachable(format!("{address}: {e}"));
    let addresses = address.to_socket_addrs().map_err(|e| unreachable(&e))?;
    let mut last = None;
    for socket in addresses {
        match TcpStream::connect_timeout(&socket, timeout) {
            Ok(stream) => return Ok(stream),
            Err(e) => last = Some(e),
        }
    }
    Err(last.map_or_else(|| unreachable(&"no address"), |e| unreachable(&e)))
}

/// Starts the thread that reads `source` line by line into a channel.
fn spawn_reader(source: impl Read + Send + 'static) -> Receiver<Item> {
    let (send, receive) = mpsc::channel();
    thread::spawn(move || {
        let mut reader = BufReader::new(source);
        loop {
            let item = read_bounded_line(&mut reader);
            let last = item.is_err();
            if send.send(item).is_err() || last {
                break;
            }
        }
    });
    receive
}

/// One line of `reader` without its newline, refusing lines longer than
/// [`MAX_LINE`] bytes without reading them whole.
///
/// # Errors
/// [`Fault::EndOfStream`] at the end (a last line without newline
/// included: the stream ended mid-line), [`Fault::LineTooLong`],
/// [`Fault::Io`].
pub fn read_bounded_line(reader: &mut impl BufRead) -> Result<Vec<u8>, Fault> {
    let mut line = Vec::new();
    loop {
        let buffer = match reader.fill_buf() {
            Ok(buffer) => buffer,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(Fault::Io(e.to_string())),
        };
        if buffer.is_empty() {
            return Err(Fault::EndOfStream);
        }
        let (chunk, found) = match buffer.iter().position(|&b| b == b'\n') {
            Some(end) => (&buffer[..end], true),
            None => (buffer, false),
        };
        if line.len() + chunk.len() > MAX_LINE {
            return Err(Fault::LineTooLong(MAX_LINE));
        }
        line.extend_from_slice(chunk);
        let used = chunk.len() + usize::from(found);
        reader.consume(used);
        if found {
            return Ok(line);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// REQ-ADP-004: a line of 64 KiB passes, one byte more is refused
    /// without being read whole.
    #[test]
    fn a_line_of_the_limit_passes_and_one_byte_more_is_refused() {
        let mut ok = vec![b'a'; MAX_LINE];
        ok.push(b'\n');
        assert_eq!(
            read_bounded_line(&mut &ok[..]).map(|l| l.len()),
            Ok(MAX_LINE)
        );
        let mut long = vec![b'a'; MAX_LINE + 1];
        long.push(b'\n');
        assert_eq!(
            read_bounded_line(&mut &long[..]),
            Err(Fault::LineTooLong(MAX_LINE))
        );
    }

    #[test]
    fn a_stream_ending_mid_line_is_its_end() {
        assert_eq!(
            read_bounded_line(&mut &b"{\"fra"[..]),
            Err(Fault::EndOfStream)
        );
        assert_eq!(read_bounded_line(&mut &b""[..]), Err(Fault::EndOfStream));
    }

    #[test]
    fn lines_split_across_reads_are_joined() {
        let data = b"ab\ncd\n";
        let mut reader = BufReader::with_capacity(1, &data[..]);
        assert_eq!(read_bounded_line(&mut reader), Ok(b"ab".to_vec()));
        assert_eq!(read_bounded_line(&mut reader), Ok(b"cd".to_vec()));
        assert_eq!(read_bounded_line(&mut reader), Err(Fault::EndOfStream));
    }
}
