;;;; Wall-clock time, the replaceable sleep, and CRAM-shaped log lines.

(in-package :cram-language)

(defun unix-time ()
  "The current wall-clock time as seconds since the Unix epoch, a double-float
with microsecond resolution."
  (multiple-value-bind (seconds microseconds) (sb-ext:get-time-of-day)
    (+ seconds (/ microseconds 1d6))))

(declaim (inline monotonic-microseconds))
(defun monotonic-microseconds ()
  "Microseconds on the system's monotonic clock (CLOCK_MONOTONIC): finer than
SBCL's internal real time, and never jumps with the wall clock."
  (multiple-value-bind (seconds nanoseconds) (sb-unix::clock-gettime 1)
    (+ (* seconds 1000000) (floor nanoseconds 1000))))

(defun check-real-seconds (seconds what)
  "Signal an error unless SECONDS is a finite non-negative real; WHAT names the
operation for the message."
  (unless (and (realp seconds)
               (not (and (floatp seconds)
                         (or (sb-ext:float-nan-p seconds)
                             (sb-ext:float-infinity-p seconds))))
               (>= seconds 0))
    (error "~a: expected a finite non-negative number of seconds, got ~s."
           what seconds))
  seconds)

(defvar *sleep-function* #'cl:sleep
  "The function that CPL:SLEEP calls with a number of seconds. A projection
environment binds it to a function that advances its own clock instead of
waiting in real time.")

(defun sleep (seconds)
  "Wait SECONDS (a finite non-negative real) by calling *SLEEP-FUNCTION*.
Inside a plan the wait can be cut short by evaporation of the task."
  (check-real-seconds seconds 'sleep)
  (funcall *sleep-function* seconds)
  nil)

;;; Logging

(defvar *log-stream* nil
  "The stream that LOG-MESSAGE writes to, or NIL (the default) for the
*STANDARD-OUTPUT* of the logging thread. A task starts with the
*STANDARD-OUTPUT* of the thread that starts it, so by default the lines of a
plan go where the output of its top-level call's caller goes (a REPL, also
one connected again after a disconnect). Bound per thread or set globally;
child tasks inherit the binding of their parent.")

(defparameter *log-flush-interval* 0.1
  "Seconds between forced flushes of the log stream: a line written sooner after
the last flush stays in the stream's buffer until the next flush (a later line,
the end of the top-level call, or the stream's own flushing). Keeps a flood of
lines from turning into one message per line on a REPL connection (SLIME), where
such a backlog delays interrupts.")

(defvar *last-log-flush* (cons nil 0)
  "The stream flushed last by LOG-MESSAGE and when (monotonic microseconds).")

(defvar *log-tags* '()
  "The list of tags LOG-INFO, LOG-WARN, LOG-ERROR and LOG-DEBUG print in front
of a message, e.g. (PICK-PLACE PICK-UP).")

(defvar *log-level* :info
  "The least severe level that is printed: one of :DEBUG, :INFO, :WARN, :ERROR.")

(defparameter +log-levels+ '(:debug :info :warn :error))

(defvar *log-lock* (bt:make-lock "cpl log")
  "Serialises writes of whole log lines.")

(defun level-rank (level)
  (or (position level +log-levels+)
      (error "Unknown log level ~s: expected one of ~{~s~^, ~}." level +log-levels+)))

(defun format-unix-time (time)
  "TIME (unix seconds) as a string with exactly three decimals."
  (multiple-value-bind (seconds fraction) (floor time)
    (let ((millis (floor (* fraction 1000))))
      (format nil "~d.~3,'0d" seconds (min millis 999)))))

(defvar *log-tally* nil
  "NIL, or an EQUAL hash table in which LOG-MESSAGE counts every line that passes
*LOG-LEVEL*, under the key (LEVEL . TAGS) (TAGS as a list), whether the line is
written or not: how often a plan logged a failure or a recovery, without anyone
formatting or reading the text. Child tasks inherit it.")

(defvar *tally-lock* (bt:make-lock "cpl log tally"))

(declaim (inline sink-stream-p))
(defun sink-stream-p (stream)
  "True when STREAM discards what is written to it: a broadcast stream without
components, such as (MAKE-BROADCAST-STREAM)."
  (and (typep stream 'broadcast-stream)
       (null (broadcast-stream-streams stream))))

(defun tally-line (level tags)
  (let ((key (cons level (if (listp tags) tags (list tags)))))
    (bt:with-lock-held (*tally-lock*)
      (incf (gethash key *log-tally* 0)))))

(defun log-message (level tags format-control &rest format-arguments)
  "Write one line `[(TAG ...) LEVEL] 1649925566.714: message' to *LOG-STREAM*
\(NIL: *STANDARD-OUTPUT*) when LEVEL (:DEBUG, :INFO, :WARN or :ERROR) is at
least *LOG-LEVEL*. TAGS is a symbol or a list of symbols. Whole lines are written atomically, so lines from
concurrent tasks do not interleave. Returns the message string, or NIL when the
level is filtered out or *LOG-STREAM* discards everything (a broadcast stream
without components): a line nobody reads is not formatted. *LOG-TALLY* counts
the line in both cases."
  (let ((rank (level-rank level)))
    (unless (stringp format-control)
      (error "log-message: expected a format control string, got ~s." format-control))
    (when (and (>= rank (level-rank *log-level*))
               (progn (when *log-tally* (tally-line level tags))
                      (not (sink-stream-p *log-stream*))))
      (let* ((message (apply #'format nil format-control format-arguments))
             (line (format nil "[~:@(~a~) ~a] ~a: ~a"
                           (if (listp tags) (format nil "~a" tags) (format nil "(~a)" tags))
                           (symbol-name level)
                           (format-unix-time (unix-time))
                           message))
             (stream (log-stream)))
        (bt:with-lock-held (*log-lock*)
          (fresh-line stream)
          (write-line line stream)
          (let ((now (monotonic-microseconds))
                (last *last-log-flush*))
            (when (or (not (eq (car last) stream))
                      (>= (- now (cdr last)) (* *log-flush-interval* 1000000)))
              (force-output stream)
              (setf *last-log-flush* (cons stream now)))))
        message))))

(defun log-stream ()
  "The stream log lines go to now: *LOG-STREAM*, or *STANDARD-OUTPUT* when it is NIL."
  (let ((stream (or *log-stream* *standard-output*)))
    (unless (streamp stream)
      (error "CPL:*LOG-STREAM* is ~s: expected an output stream, or NIL for *STANDARD-OUTPUT*."
             stream))
    stream))

(defun flush-log ()
  "Force out the log lines buffered in the current log stream."
  (let ((stream (log-stream)))
    (bt:with-lock-held (*log-lock*)
      (force-output stream)
      (setf *last-log-flush* (cons stream (monotonic-microseconds))))
    nil))

(defun log-debug (format-control &rest format-arguments)
  "Log at level :DEBUG with the tags in *LOG-TAGS*."
  (apply #'log-message :debug *log-tags* format-control format-arguments))

(defun log-info (format-control &rest format-arguments)
  "Log at level :INFO with the tags in *LOG-TAGS*."
  (apply #'log-message :info *log-tags* format-control format-arguments))

(defun log-warn (format-control &rest format-arguments)
  "Log at level :WARN with the tags in *LOG-TAGS*."
  (apply #'log-message :warn *log-tags* format-control format-arguments))

(defun log-error (format-control &rest format-arguments)
  "Log at level :ERROR with the tags in *LOG-TAGS*."
  (apply #'log-message :error *log-tags* format-control format-arguments))

(defmacro with-log-tags ((&rest tags) &body body)
  "Run BODY with TAGS (evaluated) appended to *LOG-TAGS*."
  `(let ((*log-tags* (append *log-tags* (list ,@tags))))
     ,@body))
