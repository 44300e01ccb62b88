;;;; Threads under CRAM's names (SPAWN-THREAD, SPAWN-THREADS, JOIN-THREAD ...) and string helpers.

(in-package :cram-utilities)

(defun current-thread ()
  "The thread running this call."
  sb-thread:*current-thread*)

(defun thread-alive-p (thread)
  "True while THREAD runs."
  (check-thread thread 'thread-alive-p)
  (sb-thread:thread-alive-p thread))

(defun check-thread (thread function)
  (unless (typep thread 'sb-thread:thread)
    (error "~s: expected a thread, got ~s." function thread)))

(defun spawn-thread (name function &rest arguments)
  "Start a thread named NAME (a string designator) that applies FUNCTION to ARGUMENTS; return
the thread."
  (unless (or (stringp name) (symbolp name) (characterp name))
    (error "SPAWN-THREAD: the name ~s is not a string designator." name))
  (unless (or (functionp function) (and (symbolp function) (fboundp function)))
    (error "SPAWN-THREAD: ~s is not a function." function))
  (sb-thread:make-thread (lambda () (apply function arguments)) :name (string name)))

(defun spawn-threads (n name-prefix function)
  "Start N threads named NAME-PREFIX-1 ... NAME-PREFIX-N, each calling FUNCTION with no
arguments; return them in that order."
  (unless (typep n '(integer 0))
    (error "SPAWN-THREADS: the count ~s is not a non-negative integer." n))
  (loop for i from 1 to n
        collect (spawn-thread (format nil "~a-~d" name-prefix i) function)))

(defun join-thread (thread &key timeout (on-timeout :timeout) (on-failure :error))
  "Wait for THREAD to end and return its first value. With TIMEOUT (seconds) return ON-TIMEOUT
when it has not ended by then; a thread that ended abnormally (an unhandled error, or killed)
gives ON-FAILURE."
  (check-thread thread 'join-thread)
  (when timeout
    (unless (and (realp timeout) (>= timeout 0))
      (error "JOIN-THREAD: the timeout ~s is not a non-negative number of seconds." timeout)))
  (if (eq thread sb-thread:*current-thread*)
      (error "JOIN-THREAD: a thread cannot join itself (~s)." thread)
      (let* ((marker (list 'no-value))
             (values (multiple-value-list
                      (sb-thread:join-thread thread :default marker :timeout timeout))))
        (cond ((not (eq (first values) marker)) (first values))
              ((eq (second values) :timeout) on-timeout)
              (t on-failure)))))

(defun kill-thread (thread)
  "Terminate THREAD when it is alive; true when it was."
  (check-thread thread 'kill-thread)
  (when (sb-thread:thread-alive-p thread)
    (handler-case (progn (sb-thread:terminate-thread thread) t)
      (error () nil))))

(defun replace-all (string part replacement &key (test #'char=))
  "A copy of STRING in which every occurrence of the string PART is replaced by REPLACEMENT,
scanning left to right (occurrences do not overlap). PART must not be empty."
  (unless (and (stringp string) (stringp part) (stringp replacement))
    (error "REPLACE-ALL: expected three strings, got ~s, ~s and ~s." string part replacement))
  (when (zerop (length part))
    (error "REPLACE-ALL: the part to replace is the empty string."))
  (with-output-to-string (out)
    (loop with part-length = (length part)
          for start = 0 then (+ position part-length)
          for position = (search part string :start2 start :test test)
          do (write-string string out :start start :end (or position (length string)))
          when position do (write-string replacement out)
          while position)))
