// Sends the deep-linking answer back to the LMS at once (the button stays for a person without scripts).
const form = document.getElementById('deep-link-return');
if (form && form.dataset.autosubmit === 'true') form.submit();
