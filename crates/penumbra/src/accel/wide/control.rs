//! What a batch kernel of ray casting (`kernels`, `packets`) asks of the query that runs it:
//! whether to stop, and room for results that grow as they are found. The ray-casting API's
//! options answer.

/// What a batch kernel asks of the query that runs it.
pub(crate) trait Control {
    /// The query's error.
    type Error;
    /// True when the caller asked the query to stop.
    fn cancelled(&self) -> bool;
    /// The error of a query stopped because it was cancelled.
    fn cancel_error(&self) -> Self::Error;
    /// Makes room in `v` for `additional` more values of `what`, fallibly: results that grow
    /// as they are found must not abort the process when memory runs out.
    fn grow<T>(
        &self,
        v: &mut Vec<T>,
        additional: usize,
        what: &'static str,
    ) -> Result<(), Self::Error>;
}
