//! The window and what the user does to it, gathered between frames by winit's pump.

use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::ActiveEventLoop;
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

/// What a frame acts on: the keys pressed and the drags and wheel turns since the last frame.
#[derive(Default)]
pub struct Input {
    pub keys: Vec<Action>,
    /// Pixels dragged with the left button (orbit) and with the right or middle button, or
    /// shift-left (pan).
    pub orbit: (f64, f64),
    pub pan: (f64, f64),
    /// Wheel steps, towards the look-at point positive.
    pub dolly: f64,
    pub close: bool,
    pub resized: bool,
    /// The window asked to be drawn again (exposed).
    pub redraw: bool,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Action {
    ExposureUp,
    ExposureDown,
    ExposureReset,
    NextPlane,
    PreviousPlane,
    Save,
    ResetCamera,
    Denoise,
    Quit,
}

pub struct App {
    title: String,
    size: PhysicalSize<u32>,
    pub window: Option<Window>,
    pub error: Option<String>,
    pub input: Input,
    cursor: Option<(f64, f64)>,
    left: bool,
    right: bool,
    shift: bool,
}

impl App {
    pub fn new(title: String, size: [u32; 2]) -> App {
        App {
            title,
            size: PhysicalSize::new(size[0], size[1]),
            window: None,
            error: None,
            input: Input::default(),
            cursor: None,
            left: false,
            right: false,
            shift: false,
        }
    }

    /// The input since the last call.
    pub fn take(&mut self) -> Input {
        std::mem::take(&mut self.input)
    }
}

fn action(key: &Key) -> Option<Action> {
    match key {
        Key::Named(NamedKey::Escape) => Some(Action::Quit),
        Key::Named(NamedKey::Tab) => Some(Action::NextPlane),
        Key::Character(c) => match c.as_str() {
            "+" | "=" => Some(Action::ExposureUp),
            "-" | "_" => Some(Action::ExposureDown),
            "0" => Some(Action::ExposureReset),
            "a" => Some(Action::NextPlane),
            "A" => Some(Action::PreviousPlane),
            "s" | "S" => Some(Action::Save),
            "r" | "R" => Some(Action::ResetCamera),
            "d" | "D" => Some(Action::Denoise),
            "q" | "Q" => Some(Action::Quit),
            _ => None,
        },
        _ => None,
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_some() {
            return;
        }
        let attributes = Window::default_attributes()
            .with_title(self.title.clone())
            .with_inner_size(self.size);
        match event_loop.create_window(attributes) {
            Ok(w) => self.window = Some(w),
            Err(e) => self.error = Some(format!("cannot open a window: {e}")),
        }
    }

    fn window_event(&mut self, _: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let i = &mut self.input;
        match event {
            WindowEvent::CloseRequested => i.close = true,
            WindowEvent::Resized(_) => i.resized = true,
            WindowEvent::RedrawRequested => i.redraw = true,
            WindowEvent::ModifiersChanged(m) => self.shift = m.state().shift_key(),
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                if let Some(a) = action(&event.logical_key) {
                    i.keys.push(a);
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                let down = state == ElementState::Pressed;
                match button {
                    MouseButton::Left => self.left = down,
                    MouseButton::Right | MouseButton::Middle => self.right = down,
                    _ => {}
                }
            }
            WindowEvent::CursorMoved { position, .. } => {
                let now = (position.x, position.y);
                if let Some(was) = self.cursor {
                    let d = (now.0 - was.0, now.1 - was.1);
                    let target = if self.right || (self.left && self.shift) {
                        Some(&mut i.pan)
                    } else if self.left {
                        Some(&mut i.orbit)
                    } else {
                        None
                    };
                    if let Some(t) = target {
                        t.0 += d.0;
                        t.1 += d.1;
                    }
                }
                self.cursor = Some(now);
            }
            WindowEvent::CursorLeft { .. } => self.cursor = None,
            WindowEvent::MouseWheel { delta, .. } => {
                i.dolly += match delta {
                    MouseScrollDelta::LineDelta(_, y) => f64::from(y),
                    MouseScrollDelta::PixelDelta(p) => p.y / 40.0,
                }
            }
            _ => {}
        }
    }
}
