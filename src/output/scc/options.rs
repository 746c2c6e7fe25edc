//! What a user chooses of an SCC export: measurement ID, station, channel IDs.

/// Options of the SCC export.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SccOptions {
    /// `Measurement_ID` (`YYYYMMDDccNN`); `None` = start date + station ID + `00`.
    pub measurement_id: Option<String>,
    /// Two-character EARLINET station call sign; default `ls`.
    pub station_id: String,
    /// SCC `channel_ID` of each channel, in the raw file's order; `None` = 1, 2, ….
    pub channel_ids: Option<Vec<i32>>,
}

impl Default for SccOptions {
    fn default() -> Self {
        SccOptions {
            measurement_id: None,
            station_id: "ls".to_string(),
            channel_ids: None,
        }
    }
}
