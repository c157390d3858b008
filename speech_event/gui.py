"""A window on what the robot hears, for presentations (seed D4.3.2, section 7.4).

Each text published on /speechEvent/text is shown with its time, in a font readable across a
room, errors in red, newest at the bottom and kept in view. While a person speaks, the text so far
(/speechEvent/partial) is shown dimmed on the line where the final text will come, and replaced by
it. A status line says what the node is doing: from its /diagnostics (disabled, soundDetection
down, transcribing, and the grammar in force when there is one), from the audio on
/soundDetection/signal (hearing speech), and the language and confidence of the last text
(/speechEvent/transcript). A text box publishes a typed line on /speechEvent/text as if it had
been recognised (demos without a microphone); a language switch and an enable/disable toggle call
the node's services where it offers them, and go back when the node refuses.

It talks only through the project's ports (Transport, and a service caller), so it runs on the
in-memory bus and on ROS alike. Transport callbacks come on other threads (rospy's); they queue
what they saw and the Tk main loop takes it from the queue.
"""

import argparse
import queue
import time
import tkinter as tk
from typing import Callable, List, Optional, Tuple

from speech_event.application import without_remappings
from speech_event.grammar import FREE_SPEECH
from speech_event.interfaces.diagnostics import DIAGNOSTICS_TOPIC
from speech_event.interfaces.services import SET_ENABLED_SERVICE, SET_LANGUAGE_SERVICE
from speech_event.messages import (
    NO_CONFIDENCE,
    SET_ENABLED,
    SET_LANGUAGE,
    DiagnosticArray,
    DiagnosticStatus,
    Float32MultiArray,
    ServiceType,
    SetEnabledRequest,
    SetLanguageRequest,
    String,
    TranscriptMessage,
)
from speech_event.ports import Transport
from speech_event.topics import PARTIAL_TOPIC, SIGNAL_TOPIC, TEXT_TOPIC, TRANSCRIPT_TOPIC

# (service name, its type, request) -> response; raises when the service is not there.
ServiceCall = Callable[[str, ServiceType, object], object]

ERROR_COLOUR = "#c62828"
TEXT_COLOUR = "#111111"
PARTIAL_COLOUR = "#9e9e9e"  # dimmed: the text so far, not yet what the robot acts on
POLL_MS = 50
HEARING_SECONDS = 0.5  # "hearing speech" for this long after the last block
LANGUAGES = ("english", "kinyarwanda")


def status_of(diagnostics: Optional[DiagnosticArray]) -> str:
    """The node's state in a few words, from its last diagnostics."""
    if diagnostics is None or not diagnostics.status:
        return "listening"
    status: DiagnosticStatus = diagnostics.status[0]
    values = {pair.key: pair.value for pair in status.values}
    if values.get("enabled") == "false":
        return "disabled"
    if status.level == DiagnosticStatus.ERROR:
        return "soundDetection down"
    if values.get("utterances waiting for recognition", "0") != "0" or status.level == DiagnosticStatus.WARN:
        return "transcribing"
    return "listening"


def last_text_in(transcript: Optional[object]) -> Optional[str]:
    """The language and confidence of the last final text, from its transcript message."""
    if transcript is None:
        return None
    confidence = float(getattr(transcript, "confidence", NO_CONFIDENCE))
    said = "no confidence" if confidence == NO_CONFIDENCE else f"confidence {confidence:.2f}"
    return f"{getattr(transcript, 'language', '')}, {said}"


def _is_error(text: str) -> bool:
    """The node's errors (SOUND_DETECTION_DOWN, SPEECH_NOT_RECOGNIZED) and the window's own."""
    return text.startswith("Error:")


def _is_transcription(message: object) -> bool:
    """A final text that is speech transcribed, not an error such as soundDetection being down."""
    return bool(getattr(message, "final", False)) and not _is_error(str(getattr(message, "text", "")))


def grammar_in(diagnostics: Optional[DiagnosticArray]) -> Optional[str]:
    """The grammar in force, from the node's last diagnostics; None for free speech or not known."""
    if diagnostics is None or not diagnostics.status:
        return None
    values = {pair.key: pair.value for pair in diagnostics.status[0].values}
    grammar = values.get("grammar")
    return None if grammar in (None, FREE_SPEECH) else grammar


class TranscriptWindow:
    """The Tk window: the texts published, the node's status, and the presenter's controls."""

    def __init__(
        self,
        root: tk.Tk,
        transport: Transport,
        call: ServiceCall,
        font_size: int = 28,
        clock: Callable[[], float] = time.time,
    ) -> None:
        self.root = root
        self._call = call
        self._clock = clock
        # (what, the message, when it arrived): shown with the time it came, not when Tk got to it
        self._events: queue.Queue[Tuple[str, object, float]] = queue.Queue()  # novermin
        self._diagnostics: Optional[DiagnosticArray] = None
        # What the node accepted through the toggle, until diagnostics newer than that say it
        # themselves (they come only every health_check_period).
        self._enabled_accepted: Optional[bool] = None
        self._last_transcript: Optional[object] = None
        self._last_block = float("-inf")
        self._partial_shown = False  # the last line is the dimmed text so far
        root.title("Speech Event")
        font = ("DejaVu Sans", font_size)
        self.history = tk.Text(root, font=font, wrap="word", height=8, width=40, state="disabled")
        self.history.tag_configure("error", foreground=ERROR_COLOUR)
        self.history.tag_configure("text", foreground=TEXT_COLOUR)
        self.history.tag_configure("partial", foreground=PARTIAL_COLOUR)
        self.history.pack(fill="both", expand=True)
        self.status = tk.Label(root, font=("DejaVu Sans", max(10, font_size // 2)), anchor="w")
        self.status.pack(fill="x")
        controls = tk.Frame(root)
        controls.pack(fill="x")
        self.entry = tk.Entry(controls, font=("DejaVu Sans", max(10, font_size // 2)))
        self.entry.pack(side="left", fill="x", expand=True)
        self.entry.bind("<Return>", lambda _event: self.publish_typed())
        tk.Button(controls, text="Publish", command=self.publish_typed).pack(side="left")
        self.language = tk.StringVar(root, LANGUAGES[0])
        self._language_in_force = LANGUAGES[0]
        for language in LANGUAGES:
            tk.Radiobutton(
                controls, text=language, value=language, variable=self.language, command=self.switch_language
            ).pack(side="left")
        self.enabled = tk.BooleanVar(root, True)
        tk.Checkbutton(controls, text="enabled", variable=self.enabled, command=self.toggle_enabled).pack(
            side="left"
        )
        self.publisher = transport.advertise(TEXT_TOPIC, String)
        transport.subscribe(TEXT_TOPIC, String, lambda message: self._arrived("text", message))
        transport.subscribe(PARTIAL_TOPIC, String, lambda message: self._arrived("partial", message))
        transport.subscribe(
            TRANSCRIPT_TOPIC, TranscriptMessage, lambda message: self._arrived("transcript", message)
        )
        transport.subscribe(
            DIAGNOSTICS_TOPIC, DiagnosticArray, lambda message: self._arrived("diagnostics", message)
        )
        transport.subscribe(SIGNAL_TOPIC, Float32MultiArray, lambda message: self._arrived("block", message))
        self.refresh()

    # -- what arrives ------------------------------------------------------------------------------

    def _arrived(self, kind: str, message: object) -> None:
        self._events.put((kind, message, self._clock()))

    def refresh(self) -> None:
        """Show what the transport delivered since the last call, and the status now."""
        while True:
            try:
                kind, message, when = self._events.get_nowait()
            except queue.Empty:
                break
            if kind == "text":
                self._show(str(getattr(message, "data", "")), when)
            elif kind == "partial":
                self._show(str(getattr(message, "data", "")), when, partial=True)
            elif kind == "transcript" and _is_transcription(message):
                self._last_transcript = message
            elif kind == "diagnostics" and isinstance(message, DiagnosticArray):
                self._diagnostics = message
                self._enabled_accepted = None
            elif kind == "block":
                self._last_block = when
        status = status_of(self._diagnostics)
        if self._enabled_accepted is not None:
            status = "listening" if self._enabled_accepted else "disabled"
        if status == "listening" and self._clock() - self._last_block < HEARING_SECONDS:
            status = "hearing speech"
        parts = [status]
        grammar = grammar_in(self._diagnostics)
        if grammar is not None:
            parts.append(f"grammar: {grammar}")
        last_text = last_text_in(self._last_transcript)
        if last_text is not None:
            parts.append(f"last text: {last_text}")
        self.status.configure(text=" · ".join(parts))

    def poll(self) -> None:
        self.refresh()
        self.root.after(POLL_MS, self.poll)

    def _show(self, text: str, when: float, partial: bool = False) -> None:
        """A line at the bottom; the text so far (``partial``) replaces the one before it, and
        any other line replaces the text so far."""
        stamp = time.strftime("%H:%M:%S", time.localtime(when))
        self.history.configure(state="normal")
        if self._partial_shown:
            self.history.delete("end-2l", "end-1l")
        tag = "partial" if partial else "error" if _is_error(text) else "text"
        self.history.insert("end", f"{stamp}  {text}\n", tag)
        self._partial_shown = partial
        self.history.configure(state="disabled")
        self.history.see("end")

    def lines(self) -> List[str]:
        return self.history.get("1.0", "end").splitlines()[:-1]

    # -- what the presenter does -------------------------------------------------------------------

    def publish_typed(self) -> None:
        line = self.entry.get().strip()
        if line:
            self.publisher.publish(String(data=line))
            self.entry.delete(0, "end")

    def switch_language(self) -> None:
        """Ask the node for the language chosen; refused, the button goes back to the one in force."""
        language = self.language.get()
        request = SetLanguageRequest(language=language)
        if self._ask(SET_LANGUAGE_SERVICE, SET_LANGUAGE, request, f"switch to {language}"):
            self._language_in_force = language
        else:
            self.language.set(self._language_in_force)

    def toggle_enabled(self) -> None:
        """Enable or disable the node; refused, the box goes back."""
        enabled = self.enabled.get()
        request = SetEnabledRequest(status=str(enabled).lower())
        if self._ask(SET_ENABLED_SERVICE, SET_ENABLED, request, "enable" if enabled else "disable"):
            self._enabled_accepted = enabled
            self.refresh()
        else:
            self.enabled.set(not enabled)

    def _ask(self, name: str, service: ServiceType, request: object, what: str) -> bool:
        """Call the service; whether the node accepted. A refusal or no answer is shown as a sentence."""
        try:
            response = self._call(name, service, request)
        except Exception as problem:  # the node offers no such service, or it is gone
            self._show(f"Error: could not {what}: {name} did not answer ({problem})", self._clock())
            return False
        if getattr(response, "response", 0) != 1:
            self._show(f"Error: the node refused to {what} ({name} answered 0)", self._clock())
            return False
        return True


def main(argv: Optional[List[str]] = None) -> int:
    """The window on ROS: ``python3 -m speech_event.gui`` / scripts/speech_event_gui.py."""
    parser = argparse.ArgumentParser(prog="speech_event_gui", description=__doc__)
    parser.add_argument(
        "--font-size", type=int, default=28, help="points (default 28: readable across a room)"
    )
    arguments = parser.parse_args(without_remappings(argv))  # roslaunch adds __name:= and __log:=
    from speech_event.adapters.ros import RosTransport, call_service, start_anonymous_node

    start_anonymous_node("speechEventGui")
    root = tk.Tk()
    window = TranscriptWindow(root, RosTransport(), call_service, arguments.font_size)
    window.poll()
    root.mainloop()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
