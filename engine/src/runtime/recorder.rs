//! Recording a batch of frames: one compute pass stays open across dispatches until an
//! encoder-level command (a clear, a copy, a query resolve, a submission) needs it closed.

/// Timestamp queries of one query set.
pub const MAX_QUERIES: u32 = wgpu::QUERY_SET_MAX_QUERIES;
/// Timestamp pairs in the query set.
pub const QUERY_PAIRS: usize = MAX_QUERIES as usize / 2;
/// Timestamp pairs a batch can resolve; later dispatches go untimed.
pub const MAX_TIMED: usize = 16 * QUERY_PAIRS;

/// Commands of a batch being recorded.
pub struct Recorder {
    pub encoder: wgpu::CommandEncoder,
    pass: Option<wgpu::ComputePass<'static>>,
    /// Timing slot of each timestamp pair written so far in the batch.
    pub timed: Vec<usize>,
    /// Timestamp pairs already resolved into the resolve buffer.
    resolved: usize,
    /// Host loop iterations run.
    pub host_iterations: u32,
    /// Iteration parity of the running host loop (selects ping-pong buffers).
    pub parity: usize,
    /// Dispatches recorded since the last submission.
    pub unsubmitted: u32,
}

impl Recorder {
    pub fn new(device: &wgpu::Device) -> Recorder {
        Recorder {
            encoder: device.create_command_encoder(&Default::default()),
            pass: None,
            timed: Vec::new(),
            resolved: 0,
            host_iterations: 0,
            parity: 0,
            unsubmitted: 0,
        }
    }

    /// Submits what is recorded so far and goes on in a new encoder: the GPU starts on it
    /// while the rest of the batch is recorded.
    pub fn submit(&mut self, device: &wgpu::Device, queue: &wgpu::Queue) -> wgpu::SubmissionIndex {
        self.end_pass();
        let encoder = std::mem::replace(&mut self.encoder, device.create_command_encoder(&Default::default()));
        self.unsubmitted = 0;
        queue.submit([encoder.finish()])
    }

    /// The open compute pass (opened when none is).
    pub fn pass(&mut self) -> &mut wgpu::ComputePass<'static> {
        if self.pass.is_none() {
            let pass = self.encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("lightgraph"),
                timestamp_writes: None,
            });
            self.pass = Some(pass.forget_lifetime());
        }
        self.pass.as_mut().expect("just opened")
    }

    /// Closes the compute pass, for an encoder-level command.
    pub fn end_pass(&mut self) {
        self.pass = None;
    }

    /// Sets `size` bytes of `buffer` from `offset` to zero.
    pub fn clear(&mut self, buffer: &wgpu::Buffer, offset: u64, size: u64) {
        self.end_pass();
        self.encoder.clear_buffer(buffer, offset, Some(size));
    }

    /// The query index of a new timestamp pair, resolving the set first when it is full;
    /// `None` once the batch has timed all it can.
    pub fn next_query(&mut self, queries: &Option<(wgpu::QuerySet, wgpu::Buffer)>, slot: usize) -> Option<u32> {
        if queries.is_none() || self.timed.len() >= MAX_TIMED {
            return None;
        }
        if self.timed.len() > self.resolved && self.timed.len().is_multiple_of(QUERY_PAIRS) {
            // The query set is full: resolve it before its queries are written again.
            self.resolve(queries);
        }
        let i = (self.timed.len() % QUERY_PAIRS) as u32 * 2;
        self.timed.push(slot);
        Some(i)
    }

    /// Ends the pass and resolves the timestamps written since the last resolve.
    pub fn resolve(&mut self, queries: &Option<(wgpu::QuerySet, wgpu::Buffer)>) {
        self.end_pass();
        if let Some((set, buffer)) = queries {
            let pairs = self.timed.len() - self.resolved;
            if pairs > 0 {
                let first = (self.resolved % QUERY_PAIRS) as u32 * 2;
                self.encoder
                    .resolve_query_set(set, first..first + 2 * pairs as u32, buffer, 16 * self.resolved as u64);
                self.resolved = self.timed.len();
            }
        }
    }
}
