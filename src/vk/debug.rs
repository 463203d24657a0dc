//! Validation-layer messages collected through a debug-utils messenger.

use ash::vk;
use std::ffi::CStr;
use std::sync::Mutex;

/// Validation messages (warnings and errors) reported since the last [`ValidationLog::take`].
#[derive(Debug, Default)]
pub struct ValidationLog {
    messages: Mutex<Vec<String>>,
}

impl ValidationLog {
    /// Removes and returns every message collected so far.
    pub fn take(&self) -> Vec<String> {
        std::mem::take(&mut *self.lock())
    }

    /// Number of messages waiting.
    pub fn len(&self) -> usize {
        self.lock().len()
    }

    /// True when no message is waiting.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<String>> {
        // A panicking test thread must not hide the messages of the others.
        self.messages.lock().unwrap_or_else(|p| p.into_inner())
    }

    fn push(&self, message: String) {
        self.lock().push(message);
    }
}

/// Which messages count: every warning or error from the validation layer, and errors of any kind.
pub(crate) fn messenger_info(log: &ValidationLog) -> vk::DebugUtilsMessengerCreateInfoEXT<'static> {
    vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(
            vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
        )
        .message_type(
            vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
        )
        .pfn_user_callback(Some(callback))
        .user_data(log as *const ValidationLog as *mut std::ffi::c_void)
}

unsafe extern "system" fn callback(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut std::ffi::c_void,
) -> vk::Bool32 {
    if data.is_null() || user.is_null() {
        return vk::FALSE;
    }
    // SAFETY: the layer passes valid callback data; `user` is the `ValidationLog` that the
    // context keeps alive for as long as the messenger exists.
    let (data, log) = unsafe { (&*data, &*(user as *const ValidationLog)) };
    let general_warning = kind == vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
        && severity == vk::DebugUtilsMessageSeverityFlagsEXT::WARNING;
    let text = |p: *const std::ffi::c_char| {
        if p.is_null() {
            String::new()
        } else {
            // SAFETY: non-null strings from the layer are NUL-terminated.
            unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
        }
    };
    let message =
        format!("[{severity:?} {kind:?}] {} {}", text(data.p_message_id_name), text(data.p_message));
    if general_warning {
        // Loader chatter (e.g. an ICD for absent hardware failing to load) is not a usage error.
        log::debug!("{message}");
    } else {
        log::error!("{message}");
        log.push(message);
    }
    vk::FALSE
}
